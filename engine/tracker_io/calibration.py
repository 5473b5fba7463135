"""Calibration to the wearer: body size from a standing or T-pose window, and the
tracker-to-joint offsets in that pose.

The wearer stands still for a few seconds, upright, facing any direction, on the floor
(z = 0 in the project's frame, which VR stage spaces provide):

1. **Height.** The head tracker's mean height is taken as the head joint's
   (``upperneck``, about ear level, which is also eye level: a headset sits in front of
   the joint, not above it). The canonical skeleton is scaled by ``s`` so that its rest
   head joint is at that height with the toes at the clips' toe height
   (4.5 cm x ``s``, the re-flooring rule of ``docs/skeleton.md``). Without a head
   tracker the hip tracker's height is used the same way.
2. **Arm span (T-pose only).** The distance between the two hand trackers is matched by
   scaling the arm chains (shoulder, elbow, wrist offsets) by ``a`` (bisection); in a
   standing pose (arms down) the arms keep the body's scale, ``a = s``. The pose is
   detected from the hands (far apart and near shoulder height: T-pose) unless given.
3. **Offsets.** The scaled rest pose is placed in the world: heading from the hands
   (T-pose) or the feet (standing), else from the head tracker; horizontally so that the
   mean of the tracked joints is the mean of the trackers; root height from the floor.
   For every 6-DoF tracker whose joint is where the rest pose says (all in a T-pose; all
   but the hands when standing), the offset from tracker to joint is stored in the
   tracker's frame: ``o = R_t^-1 (p_j - p_t)`` and ``R_o = R_t^-1 R_j``. Afterwards each
   reading becomes ``p = p_t + R_t o``, ``R = R_t R_o``.

What one still pose cannot tell apart: a common horizontal shift of every tracker from
its joint (absorbed by the placement, so every offset is off by the trackers' mean
offset), a headset mounted above the eye line (it adds to the height), and controllers
held beyond the wrists (they add to the span). ``docs/trackers.md`` gives the figures.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

from engine import skeleton as sk
from engine.errors import UserError
from engine.kinematics import quaternion as Q
from engine.methods import SensorFrame

#: Height of the toe joint above the floor for a scale-1 skeleton (``engine.motion.retarget``).
TOE_HEIGHT_M = 0.045
ARM_JOINTS = ("lshoulder", "lelbow", "lwrist", "rshoulder", "relbow", "rwrist")
_ARM_IDX = [sk.JOINT_INDEX[j] for j in ARM_JOINTS]
_HAND_SLOTS = ("lwrist", "rwrist")


@dataclass
class Calibration:
    """The result of :func:`calibrate`.

    Attributes
    ----------
    skeleton : Skeleton
        The wearer's skeleton (body scale ``scale``, arms ``arm_scale``).
    scale, arm_scale : float
        Relative to the canonical skeleton.
    height_m : float
        ``skeleton.height()``, metres.
    arm_span_m : float or None
        Measured distance between the hand trackers (T-pose), metres.
    pose : str
        ``"tpose"`` or ``"standing"``.
    offsets : dict of str -> (ndarray (3,), ndarray (4,))
        Joint -> (position offset in the tracker's frame, metres; rotation offset w, x, y, z).
    frames : int
        Frames averaged.
    """

    skeleton: sk.Skeleton
    scale: float
    arm_scale: float
    height_m: float
    arm_span_m: float | None
    pose: str
    offsets: dict[str, tuple[np.ndarray, np.ndarray]] = field(default_factory=dict)
    frames: int = 0

    def apply(
        self, joint: str, position: np.ndarray, rotation: np.ndarray, dof: int = 6
    ) -> tuple[np.ndarray, np.ndarray]:
        """Joint pose from a tracker pose (unchanged for 3-DoF or uncalibrated joints)."""
        off = self.offsets.get(joint)
        if off is None or dof != 6:
            return position, rotation
        o, r = off
        return position + Q.rotate(rotation, o), Q.normalize(Q.mul(rotation, r))

    def to_json(self) -> dict:
        return {
            "pose": self.pose,
            "scale": self.scale,
            "arm_scale": self.arm_scale,
            "height_m": self.height_m,
            "arm_span_m": self.arm_span_m,
            "frames": self.frames,
            "offsets": {
                j: {"pos": o.round(5).tolist(), "quat": r.round(6).tolist()} for j, (o, r) in self.offsets.items()
            },
        }

    def summary(self) -> str:
        span = f", arm span {self.arm_span_m:.3f} m" if self.arm_span_m else ""
        return (
            f"calibrated ({self.pose}, {self.frames} frames): height {self.height_m:.3f} m "
            f"(scale {self.scale:.3f}, arms {self.arm_scale:.3f}){span}; offsets for {', '.join(self.offsets) or 'none'}"
        )


def scaled_skeleton(scale: float, arm_scale: float | None = None) -> sk.Skeleton:
    """The canonical skeleton scaled by ``scale``, its arm chains by ``arm_scale``."""
    off = sk.REST_OFFSETS * float(scale)
    if arm_scale is not None:
        off[_ARM_IDX] = sk.REST_OFFSETS[_ARM_IDX] * float(arm_scale)
    return sk.Skeleton(off)


def standing_root_height(skeleton: sk.Skeleton) -> float:
    """Root height of the rest pose standing on the floor (toes at the toe height), m."""
    rest = skeleton.rest_positions()
    return TOE_HEIGHT_M * skeleton.scale - rest[sk.JOINT_INDEX["ltoe"], 2]


def _mean_pose(frames: Sequence[SensorFrame]) -> dict[str, tuple[np.ndarray, np.ndarray, int]]:
    """Joint -> (mean position, mean rotation, dof) over the connected readings."""
    acc: dict[str, list] = {}
    for f in frames:
        for j, r in f.connected().items():
            acc.setdefault(j, []).append(r)
    out = {}
    for j, rs in acc.items():
        if len(rs) < max(1, len(frames) // 2):
            continue  # lost for most of the window: not trusted
        pos = np.mean([r.position for r in rs], axis=0)
        q = np.array([r.rotation for r in rs])
        q = q * np.where((q @ q[0]) < 0, -1.0, 1.0)[:, None]  # one hemisphere
        out[j] = (pos, Q.normalize(q.mean(axis=0)), rs[0].dof)
    return out


def _yaw(left: np.ndarray) -> np.ndarray:
    """Heading quaternion turning the rest pose's left (+X) onto ``left`` (horizontal)."""
    a = math.atan2(left[1], left[0])
    return np.array([math.cos(a / 2), 0.0, 0.0, math.sin(a / 2)])


def calibrate(frames: Sequence[SensorFrame], pose: str = "auto") -> Calibration:
    """Estimate the wearer's skeleton and tracker offsets from a still window.

    Parameters
    ----------
    frames : sequence of SensorFrame
        Readings of the raw trackers (no calibration applied), project frame.
    pose : str
        ``"auto"`` (detect), ``"tpose"`` or ``"standing"``.

    Raises
    ------
    UserError
        Without frames, without a head or hip tracker, or for an implausible height.
    """
    if pose not in ("auto", "tpose", "standing"):
        raise UserError(f"calibration pose must be auto, tpose or standing, got {pose!r}")
    mean = _mean_pose(frames)
    if not mean:
        raise UserError("calibration: no tracker was connected during the window")
    unit = sk.Skeleton.canonical()
    rest1 = unit.rest_positions()
    root1 = standing_root_height(unit)
    if "upperneck" in mean:
        scale = mean["upperneck"][0][2] / (rest1[sk.JOINT_INDEX["upperneck"], 2] + root1)
    elif "root" in mean:
        scale = mean["root"][0][2] / root1
    else:
        raise UserError("calibration needs a head or a hip tracker")
    if not 0.5 <= scale <= 1.5:
        height = (mean["upperneck"] if "upperneck" in mean else mean["root"])[0][2]
        raise UserError(
            f"calibration: the head is at {height:.2f} m, "
            f"an implausible size (scale {scale:.2f}); is the floor at z = 0 and the wearer standing?"
        )

    hands = all(h in mean for h in _HAND_SLOTS)
    span = float(np.linalg.norm(mean["lwrist"][0] - mean["rwrist"][0])) if hands else None
    body = scaled_skeleton(scale)
    rest = body.rest_positions()
    if pose == "auto":
        pose = "standing"
        if hands:
            rest_span = float(np.linalg.norm(rest[sk.JOINT_INDEX["lwrist"]] - rest[sk.JOINT_INDEX["rwrist"]]))
            shoulder_z = rest[sk.JOINT_INDEX["lshoulder"], 2] + standing_root_height(body)
            hand_z = 0.5 * (mean["lwrist"][0][2] + mean["rwrist"][0][2])
            if span is not None and span > 0.75 * rest_span and abs(hand_z - shoulder_z) < 0.25 * scale:
                pose = "tpose"
    if pose == "tpose" and span is None:  # span: both hands
        raise UserError("calibration: a T-pose needs both hand trackers")
    arm = _arm_scale(scale, span) if pose == "tpose" and span is not None else scale
    skel = scaled_skeleton(scale, arm)
    offsets = _offsets(mean, skel, pose)
    return Calibration(
        skel, float(scale), float(arm), skel.height(), span if pose == "tpose" else None, pose, offsets, len(frames)
    )


def _arm_scale(scale: float, span: float) -> float:
    lw, rw = sk.JOINT_INDEX["lwrist"], sk.JOINT_INDEX["rwrist"]

    def width(a: float) -> float:
        p = scaled_skeleton(scale, a).rest_positions()
        return float(np.linalg.norm(p[lw] - p[rw]))

    lo, hi = 0.3 * scale, 3.0 * scale
    if not width(lo) <= span <= width(hi):
        raise UserError(f"calibration: hand trackers {span:.2f} m apart do not fit a body of scale {scale:.2f}")
    for _ in range(60):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if width(mid) < span else (lo, mid)
    return 0.5 * (lo + hi)


def _offsets(mean: dict, skel: sk.Skeleton, pose: str) -> dict[str, tuple[np.ndarray, np.ndarray]]:
    """Place the rest pose at the trackers and measure each tracker's offset."""
    joints = [j for j in mean if pose == "tpose" or j not in _HAND_SLOTS]
    if pose == "tpose":
        left = mean["lwrist"][0] - mean["rwrist"][0]
    elif "lankle" in mean and "rankle" in mean:
        left = mean["lankle"][0] - mean["rankle"][0]
    elif "upperneck" in mean and mean["upperneck"][2] == 6:
        left = Q.rotate(Q.heading(mean["upperneck"][1]), sk.LEFT)
    else:
        left = np.array(sk.LEFT)
    heading = _yaw(left)
    rest = skel.rest_positions()
    rest[:, 2] += standing_root_height(skel)
    idx = [sk.JOINT_INDEX[j] for j in joints]
    world = Q.rotate(np.broadcast_to(heading, (len(idx), 4)), rest[idx])
    trackers = np.array([mean[j][0] for j in joints])
    shift = (trackers - world).mean(axis=0)
    shift[2] = 0.0  # height is set by the floor, not by the trackers
    out = {}
    for k, j in enumerate(joints):
        pos_t, rot_t, dof = mean[j]
        if dof != 6:
            continue
        inv = Q.conjugate(rot_t)
        out[j] = (Q.rotate(inv, world[k] + shift - pos_t), Q.normalize(Q.mul(inv, heading)))
    return out
