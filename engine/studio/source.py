"""Where the engine thread's sensor readings come from.

A :class:`SensorSource` gives, per frame, the readings of the session's sensors with
the studio's edits applied (disabled sensors dropped, 3-DoF sensors without rotation,
simulated failures disconnected, drag offsets added), plus the reference pose drawn
as "ground truth" when there is one. :class:`ClipSource` simulates trackers from a
loaded clip (:func:`engine.tracking.simulate`); other sources (recordings, live
trackers) implement the same four members and are installed with
:class:`engine.studio.commands.SetSource`.
"""

from __future__ import annotations

from abc import ABC, abstractmethod

import numpy as np

from engine import skeleton as sk
from engine.errors import UserError
from engine.motion import Motion
from engine.sensors import Sensor, SensorFrame
from engine.tracking import Tracking, simulate


class SensorSource(ABC):
    """Per-frame sensor readings for the engine thread (see the module doc)."""

    #: The session's sensors, settings only (set by the engine thread on every change).
    sensors: tuple[Sensor, ...] = ()
    #: The clip behind the source, when there is one (methods are reset with it).
    motion: Motion | None = None

    @property
    @abstractmethod
    def fps(self) -> float:
        """Frames per second of the stream."""

    @property
    @abstractmethod
    def num_frames(self) -> int:
        """Frames available (0 while there are none)."""

    @abstractmethod
    def frame(self, frame: int) -> SensorFrame:
        """Readings of the enabled sensors at ``frame`` with the studio's edits applied."""

    def ground_truth(self, frame: int) -> np.ndarray:
        """Reference world joint positions (22, 3), metres; NaN when there is none."""
        return np.full((sk.NUM_JOINTS, 3), np.nan)

    def set_sensors(self, sensors: tuple[Sensor, ...]) -> None:
        self.sensors = tuple(sensors)


def apply_edits(sensor: Sensor, reading: Sensor, frame: int) -> Sensor:
    """``reading`` (the raw sample) with ``sensor``'s offset, DoF and failures applied."""
    position = np.asarray(reading.position, float) + np.asarray(sensor.offset, float)
    rotation = np.asarray(reading.rotation, float)
    if sensor.dof == 3:
        rotation = np.array([1.0, 0.0, 0.0, 0.0])  # position-only: no ground truth leaks through
    return sensor.read(position, rotation, bool(reading.connected) and not sensor.lost_at(frame))


class ClipSource(SensorSource):
    """Trackers simulated from a clip's forward kinematics (no noise, no failures
    except the studio's own simulated ones)."""

    def __init__(self, motion: Motion) -> None:
        self.motion = motion
        self.gt_positions, _ = motion.fk()
        self.sensors = ()
        self._tracking: Tracking | None = None

    @property
    def fps(self) -> float:
        return float(self.motion.fps)

    @property
    def num_frames(self) -> int:
        return len(self.motion)

    def ground_truth(self, frame: int) -> np.ndarray:
        return self.gt_positions[frame]

    def set_sensors(self, sensors: tuple[Sensor, ...]) -> None:
        joints_changed = [s.joint for s in sensors] != [s.joint for s in self.sensors]
        self.sensors = tuple(sensors)
        if joints_changed or self._tracking is None:
            self._tracking = self._simulate()

    def _simulate(self) -> Tracking | None:
        if not self.sensors:
            return None
        try:
            # 6-DoF streams for all: the DoF each sensor reports is the studio's setting
            return simulate(self.motion, [Sensor(s.joint) for s in self.sensors])
        except UserError as exc:
            raise UserError(f"clip {self.motion.name!r}: cannot simulate sensors ({exc})") from exc

    def frame(self, frame: int) -> SensorFrame:
        readings: dict[str, Sensor] = {}
        if self._tracking is not None:
            base = self._tracking.frame(frame).readings
            for s in self.sensors:
                if s.enabled:
                    readings[s.joint] = apply_edits(s, base[s.joint], frame)
        return SensorFrame(frame, readings)
