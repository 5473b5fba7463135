"""SparsePoser as a method (``--method sparseposer``): six 6-DoF trackers, preset ``6``.

Per frame the trackers become root-space dual quaternions (the root slot holds the hip
tracker's rotation in the previous frame's heading and its displacement), appended to a
window of the last ``T`` frames (64; at the start of a clip the first frame is
repeated). The generator decodes the window's last frame (only its tail is decoded,
which gives the same last frame as a full decode), the learned IK moves each limb
towards its tracker, and the root takes the hip tracker's position and rotation, as
in the paper.

**Future frames.** The paper's realtime variant (*Ours-0*) sees no future frames and an
offline variant sees 7. Methods here are fed one frame at a time, so this is the
realtime variant in both ``--mode`` settings; the model is trained with extra weight
on the window's last frame for that reason (``engine/training/sparseposer.py``).

A lost tracker (``connected`` False) keeps feeding its last connected reading: the
paper's method has no notion of tracking loss.
"""

from __future__ import annotations

import time
from collections import deque
from typing import Any

import numpy as np
import pymotion.rotations.dual_quat_np as dq_np
import torch

from engine import skeleton as sk
from engine.kinematics import quaternion as Q
from engine.kinematics.fk import fk
from engine.methods.base import FrameResult, Method, check_preset
from engine.sensors import Sensor, SensorFrame
from engine.models.sparseposer import SPARSE_INDEX, SPARSE_JOINTS
from engine.motion import Motion

#: Decoder frames evaluated per step (the last output frame equals the full decode's).
TAIL = 8


class SparsePoserMethod(Method):
    """Generator + learned IK over a sliding window of tracker frames.

    Parameters
    ----------
    model : SparsePoser, optional
        Default: the shipped ``assets/models/sparseposer.pt``.
    sparseposer_path : path, optional
        Load the weights from this file instead.
    **_unused
        Optimizer keywords meant for other methods (``mode``, ``iterations``...), ignored.
    """

    name = "sparseposer"

    def __init__(self, model: Any = None, sparseposer_path: Any = None, **_unused: Any) -> None:
        if model is None:
            from engine.models.loading import load_sparseposer

            model, _ = load_sparseposer(sparseposer_path)
        self.model = model.eval().requires_grad_(False)
        self.window = model.config.window
        self.reset(sk.Skeleton.canonical())

    def reset(self, skeleton: sk.Skeleton, fps: float = sk.FPS, *, reference: Motion | None = None) -> None:
        self.skeleton = skeleton
        self.offsets = np.asarray(skeleton.offsets, dtype=np.float64)
        self._off_t = torch.as_tensor(self.offsets, dtype=torch.float32)[None]
        self._frames: deque[np.ndarray] = deque(maxlen=self.window)
        self._last: dict[str, Sensor] = {}
        self._prev_root: tuple[np.ndarray, np.ndarray] | None = None

    def _reading(self, frame: SensorFrame, joint: str) -> Sensor:
        r = frame.readings[joint]
        ok = r.connected and np.all(np.isfinite(r.position)) and np.all(np.isfinite(r.rotation))
        if ok or joint not in self._last:
            self._last[joint] = r
        return self._last[joint]

    def features(self, frame: SensorFrame) -> np.ndarray:
        """Raw root-space dual quaternions ``(22, 8)`` of this frame (zeros off the trackers)."""
        check_preset(frame.readings, SPARSE_JOINTS, self.name, "6")
        rd = {j: self._reading(frame, j) for j in SPARSE_JOINTS}
        r_rot = Q.normalize(np.asarray(rd["root"].rotation, dtype=np.float64))
        r_pos = np.asarray(rd["root"].position, dtype=np.float64)
        prev_rot, prev_pos = self._prev_root or (r_rot, r_pos)
        self._prev_root = (r_rot, r_pos)
        h_inv = Q.conjugate(Q.heading(prev_rot))
        rots = np.zeros((len(SPARSE_JOINTS), 4))
        poss = np.zeros((len(SPARSE_JOINTS), 3))
        rots[0], poss[0] = Q.mul(h_inv, r_rot), Q.rotate(h_inv, r_pos - prev_pos)
        inv = Q.conjugate(r_rot)
        for k, j in enumerate(SPARSE_JOINTS[1:], start=1):
            rots[k] = Q.mul(inv, Q.normalize(np.asarray(rd[j].rotation, dtype=np.float64)))
            poss[k] = Q.rotate(inv, np.asarray(rd[j].position, dtype=np.float64) - r_pos)
        out = np.zeros((sk.NUM_JOINTS, 8))
        out[list(SPARSE_INDEX)] = dq_np.from_rotation_translation(Q.canonicalize(rots), poss)
        return out

    def step(self, sensors: SensorFrame) -> FrameResult:
        t0 = time.perf_counter()
        self._frames.append(self.features(sensors))
        frames = list(self._frames)
        frames = [frames[0]] * (self.window - len(frames)) + frames
        window = torch.as_tensor(np.stack(frames), dtype=torch.float32)[None]
        with torch.no_grad():
            local_ik, _ = self.model(window, self._off_t, tail=TAIL)
        local = Q.canonicalize(local_ik[0].double().numpy())
        root_rot, root_pos = self._prev_root  # this frame's hip tracker
        local[0] = root_rot
        pos, _ = fk(local, root_pos, self.offsets)
        return FrameResult(local, root_pos.copy(), pos, ms=1000.0 * (time.perf_counter() - t0))


def create(**kwargs: Any) -> SparsePoserMethod:
    """Registry factory (``mode``/``iterations`` are accepted and ignored)."""
    return SparsePoserMethod(**kwargs)
