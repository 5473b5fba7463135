"""Sensor readings the engine thread feeds to the method, from a clip and a sensor set.

The base readings come from :mod:`engine.tracking`'s simulation when it is available,
else straight from the clip's forward kinematics (perfect trackers). The studio's
per-sensor settings (:class:`engine.session.SensorConfig`) are applied on top: disabled
sensors are dropped, 3-DoF sensors lose their rotation, simulated failures disconnect
the sensor and drag offsets move its target.
"""

from __future__ import annotations

import importlib
from typing import Any

import numpy as np

from engine import skeleton as sk
from engine.methods.base import SensorFrame, SensorReading
from engine.motion import Motion
from engine.session import SensorConfig


class SensorSource:
    """Per-frame :class:`SensorFrame` for the current clip and sensor set."""

    def __init__(self) -> None:
        self.motion: Motion | None = None
        self.gt_positions = np.zeros((0, sk.NUM_JOINTS, 3))
        self.gt_rotations = np.zeros((0, sk.NUM_JOINTS, 4))
        self._sensors: tuple[SensorConfig, ...] = ()
        self._tracking: Any = None

    @property
    def fps(self) -> float:
        return self.motion.fps if self.motion is not None else sk.FPS

    @property
    def num_frames(self) -> int:
        return 0 if self.motion is None else len(self.motion)

    @property
    def sensors(self) -> tuple[SensorConfig, ...]:
        return self._sensors

    @sensors.setter
    def sensors(self, value: tuple[SensorConfig, ...]) -> None:
        joints_changed = {s.joint for s in value} != {s.joint for s in self._sensors}
        self._sensors = tuple(value)
        if joints_changed:
            self._tracking = self._simulate()

    def set_motion(self, motion: Motion) -> None:
        self.motion = motion
        self.gt_positions, self.gt_rotations = motion.fk()
        self._tracking = self._simulate()

    def _simulate(self) -> Any:
        """The tracking module's simulated trackers, or None to read the clip directly."""
        if self.motion is None or not self._sensors:
            return None
        try:
            tracking = importlib.import_module("engine.tracking")
            simulate = getattr(tracking, "simulate")
        except (ImportError, AttributeError):
            return None
        try:
            return simulate(self.motion, [s.joint for s in self._sensors])
        except Exception:  # interface mismatch: fall back to perfect trackers
            return None

    def _base(self, frame: int) -> dict[str, SensorReading]:
        if self._tracking is not None:
            try:
                return dict(self._tracking.frame(frame).readings)
            except Exception:
                self._tracking = None
        out = {}
        for s in self._sensors:
            j = sk.JOINT_INDEX[s.joint]
            out[s.joint] = SensorReading(s.joint, self.gt_positions[frame, j], self.gt_rotations[frame, j])
        return out

    def frame(self, frame: int) -> SensorFrame:
        """Readings of the enabled sensors at ``frame`` with the studio's edits applied."""
        base = self._base(frame)
        readings = {}
        for s in self._sensors:
            if not s.enabled or s.joint not in base:
                continue
            r = base[s.joint]
            readings[s.joint] = SensorReading(
                joint=s.joint,
                position=np.asarray(r.position, float) + np.asarray(s.offset, float),
                rotation=np.asarray(r.rotation, float),
                dof=s.dof,
                connected=bool(r.connected) and not s.lost_at(frame),
            )
        return SensorFrame(frame, readings)
