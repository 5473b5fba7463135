"""The studio's sensor source for a loaded clip: trackers simulated from its motion.

:class:`ClipSource` implements :class:`engine.sensor_source.SensorSource` with
:func:`engine.tracking.simulate` (6-DoF streams for every sensor; the DoF, offsets and
failures are the studio's edits, :func:`engine.sensor_source.apply_edits`). The clip is
the ground truth drawn beside the reconstruction.
"""

from __future__ import annotations

import numpy as np

from engine.errors import UserError
from engine.motion.clip import Motion
from engine.sensor_source import SensorSource, apply_edits
from engine.sensors import Sensor, SensorFrame
from engine.tracking import Tracking, simulate


class ClipSource(SensorSource):
    """Trackers simulated from a clip's forward kinematics (no noise, no failures
    except the studio's own simulated ones)."""

    motion: Motion  # always a clip here

    def __init__(self, motion: Motion) -> None:
        self.motion = motion
        self.skeleton = motion.skeleton
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
        if self._tracking is None:
            return SensorFrame(frame, {})
        return apply_edits(self._tracking.frame(frame).readings, self.sensors, frame)
