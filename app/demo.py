"""A procedural walk on the canonical skeleton, shown when no clip is available."""

from __future__ import annotations

import numpy as np

from engine import skeleton as sk
from engine.kinematics import quaternion as Q
from engine.motion.clip import Motion


def _axis(angle: np.ndarray, axis: tuple[float, float, float]) -> np.ndarray:
    return Q.from_axis_angle(np.broadcast_to(np.asarray(axis, float), angle.shape + (3,)), angle)


def demo_walk(seconds: float = 6.0, fps: float = sk.FPS) -> Motion:
    """Walk forward (-Y) at 1.1 m/s with swinging arms; deterministic, ``seconds`` long."""
    t = np.arange(int(seconds * fps)) / fps
    phase = 2 * np.pi * 0.9 * t
    rot = np.tile(np.array([1.0, 0.0, 0.0, 0.0]), (len(t), sk.NUM_JOINTS, 1))
    j = sk.JOINT_INDEX
    for side, sign in (("l", 1.0), ("r", -1.0)):
        swing = sign * np.sin(phase)
        rot[:, j[f"{side}hip"]] = _axis(-0.45 * swing, (1, 0, 0))
        rot[:, j[f"{side}knee"]] = _axis(0.55 * np.clip(np.sin(phase * 1.0 + sign * 1.2), 0, None) + 0.08, (1, 0, 0))
        rot[:, j[f"{side}ankle"]] = _axis(0.15 * swing, (1, 0, 0))
        down = _axis(np.full_like(t, sign * 1.25), (0, 1, 0))
        rot[:, j[f"{side}shoulder"]] = Q.mul(_axis(0.4 * swing, (1, 0, 0)), down)
        rot[:, j[f"{side}elbow"]] = _axis(np.full_like(t, -sign * 0.35), (0, 0, 1))
    rot[:, j["chest"]] = _axis(0.06 * np.sin(phase), (0, 0, 1))
    rot[:, 0] = _axis(0.05 * np.sin(phase), (0, 0, 1))
    root = np.stack([0.03 * np.sin(phase), -1.1 * t, 1.0 + 0.02 * np.cos(2 * phase)], axis=-1)
    return Motion(rot, root, sk.Skeleton.canonical(), fps, "demo walk")
