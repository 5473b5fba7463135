"""RPM as a method (``--method rpm``): head and hands, preset ``3-head-hands``.

Each frame: the last ``I + 1`` tracker samples (a lost hand reads as empty) and the last
``M`` output poses go through the network; PCAF corrects the rolling prediction of the
next ``W`` poses; its first pose is the output; the window rolls on (see
:mod:`engine.models.rpm`). The first frame starts from the blank (mean) pose, so the
first few tenths of a second settle in (RPM's evaluation skips the first second).
The root is placed so that the pose's head meets the head tracker; a lost head holds
its last reading.
"""

from __future__ import annotations

import time
from collections import deque
from typing import Any

import numpy as np
import pymotion.rotations.ortho6d_torch as o6
import torch

from engine import skeleton as sk
from engine.kinematics import quaternion as Q
from engine.kinematics.fk import fk
from engine.methods.base import FrameResult, Method, check_preset
from engine.methods.presets import REQUIRED_PRESET
from engine.models.rpm import RPM_JOINTS, blank_pose, roll, rolling_step, track_features, yaw_matrix
from engine.motion.clip import Motion
from engine.sensors import Sensor, SensorFrame

_HEAD = sk.JOINT_INDEX["upperneck"]


class RPMMethod(Method):
    """Rolling Prediction Model with PCAF.

    Parameters
    ----------
    model : RPM, optional
        Default: the shipped ``assets/models/rpm.pt``.
    rpm_path : path, optional
        Load the weights from this file instead.
    **_unused
        Keywords meant for other methods, ignored.
    """

    name = "rpm"

    def __init__(self, model: Any = None, rpm_path: Any = None, **_unused: Any) -> None:
        if model is None:
            from engine.models.loading import load_rpm

            model, _ = load_rpm(rpm_path)
        self.model = model.eval().requires_grad_(False)
        self.reset(sk.Skeleton.canonical())

    def reset(self, skeleton: sk.Skeleton, fps: float = sk.FPS, *, reference: Motion | None = None) -> None:
        self.skeleton = skeleton
        self.offsets = np.asarray(skeleton.offsets, dtype=np.float64)
        n = self.model.config.past_inputs + 1
        self._pos: deque[np.ndarray] = deque(maxlen=n)
        self._rot: deque[np.ndarray] = deque(maxlen=n)
        self._flags: deque[np.ndarray] = deque(maxlen=n)
        self._head: Sensor | None = None
        self._P: torch.Tensor | None = None
        self._ctx: torch.Tensor | None = None

    def _sample(self, frame: SensorFrame) -> None:
        check_preset(frame.readings, RPM_JOINTS, self.name, REQUIRED_PRESET["rpm"])
        pos, rot, flags = np.zeros((3, 3)), np.tile([1.0, 0.0, 0.0, 0.0], (3, 1)), np.zeros(3, dtype=bool)
        for k, j in enumerate(RPM_JOINTS):
            r = frame.readings[j]
            ok = bool(
                r.connected
                and r.position is not None
                and r.rotation is not None
                and np.all(np.isfinite(r.position))
                and np.all(np.isfinite(r.rotation))
            )
            if j == "upperneck":
                if ok or self._head is None:
                    self._head = r
                r, ok = self._head, True
            if ok:
                pos[k], rot[k], flags[k] = r.position, Q.normalize(np.asarray(r.rotation, dtype=np.float64)), True
        # the history starts full, with copies of the first sample
        for _ in range(1 if self._pos else self._pos.maxlen or 1):
            self._pos.append(pos)
            self._rot.append(rot)
            self._flags.append(flags)

    def step(self, sensors: SensorFrame, deadline: float | None = None) -> FrameResult:
        t0 = time.perf_counter()
        self._sample(sensors)
        cfg = self.model.config
        pos = torch.as_tensor(np.stack(self._pos), dtype=torch.float32)[None]
        rot6 = o6.from_quat(torch.as_tensor(np.stack(self._rot), dtype=torch.float32))[None]
        flags = torch.as_tensor(np.stack(self._flags))[None]
        head_pos = pos[:, -1, 0]
        h = yaw_matrix(torch.as_tensor(self._rot[-1][0], dtype=torch.float32))[None]
        origin = head_pos * torch.tensor([1.0, 1.0, 0.0])
        with torch.no_grad():
            if self._P is None or self._ctx is None:
                blank = blank_pose(self.model, h)[:, None]
                self._P = blank.expand(-1, cfg.window, -1, -1, -1).clone()
                self._ctx = blank.expand(-1, cfg.past_poses, -1, -1, -1).clone()
            track = track_features(pos, rot6, flags, h, origin)
            self._P = rolling_step(self.model, self._P, self._ctx, track, h)
            pose6 = self._P[0, 0]
            self._P, self._ctx = roll(self._P, self._ctx, blank_pose(self.model, h))
        local = Q.canonicalize(o6.to_quat(pose6.double()).numpy())
        p0, _ = fk(local, np.zeros(3), self.offsets)
        root = self._pos[-1][0] - p0[_HEAD]
        return FrameResult(local, root, p0 + root, ms=1000.0 * (time.perf_counter() - t0))


def create(**kwargs: Any) -> RPMMethod:
    """Registry factory (``mode``/``iterations`` are accepted and ignored)."""
    return RPMMethod(**kwargs)
