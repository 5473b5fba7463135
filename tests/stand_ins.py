"""Methods that stand in for the real ones in tests: cheap, deterministic, no models."""

from __future__ import annotations

import time

import numpy as np

from engine import skeleton as sk
from engine.kinematics import quaternion as Q
from engine.kinematics.fk import fk
from engine.methods.base import FrameResult, Method
from engine.sensors import SensorFrame


class RestPoseMethod(Method):
    """The rest pose carried by the hip (or head) tracker.

    Lets the studio run end to end without models. Its loss terms are the squared
    position errors of every connected tracker.
    """

    name = "rest"

    def reset(self, skeleton: sk.Skeleton, fps: float = sk.FPS, **_: object) -> None:
        self._offsets = skeleton.offsets
        self._rest = skeleton.rest_positions()
        self._root = np.array([0.0, 0.0, -self._rest[:, 2].min() + 0.05])
        self._rot = np.array([1.0, 0.0, 0.0, 0.0])

    def step(self, sensors: SensorFrame, deadline: float | None = None) -> FrameResult:
        t0 = time.perf_counter()
        conn = sensors.connected()
        if "root" in conn:
            self._root = np.asarray(conn["root"].position, float)
            if conn["root"].dof == 6:
                self._rot = np.asarray(conn["root"].rotation, float)
        elif "upperneck" in conn:
            head = self._rest[sk.JOINT_INDEX["upperneck"]]
            self._root = np.asarray(conn["upperneck"].position, float) - Q.rotate(self._rot, head)
        local = np.tile(np.array([1.0, 0.0, 0.0, 0.0]), (sk.NUM_JOINTS, 1))
        local[0] = self._rot
        pos, _ = fk(local, self._root, self._offsets)
        losses = {f"pos:{j}": float(np.sum((pos[sk.JOINT_INDEX[j]] - r.position) ** 2)) for j, r in conn.items()}
        losses["total"] = float(sum(losses.values()))
        return FrameResult(local, self._root.copy(), pos, 1, [losses], None, (time.perf_counter() - t0) * 1e3)
