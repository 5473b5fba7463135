"""A tracker recording as the studio's sensor source (:class:`engine.sensor_source.SensorSource`):
it opens like a clip, with the timeline, and has no ground truth (``ground_truth`` is NaN)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from engine import skeleton as sk
from engine.sensor_source import SensorSource, apply_edits
from engine.sensors import SensorFrame
from engine.tracker_io.calibration import Calibration, calibrate
from engine.tracker_io.live import calibration_window
from engine.tracker_io.recording import Recording, read_recording, replay


class RecordingSource(SensorSource):
    """Frames of a recording (:mod:`engine.tracker_io.recording`), replayed as live.

    Parameters
    ----------
    recording : Recording or path
    calibrate_s : float
        Calibrate from the first ``calibrate_s`` seconds (0: none; the canonical
        skeleton is used). The calibration frames stay on the timeline.
    """

    def __init__(self, recording: Recording | str | Path, calibrate_s: float = 0.0) -> None:
        self.recording = recording if isinstance(recording, Recording) else read_recording(recording)
        self.name = self.recording.path.stem if self.recording.path else "recording"
        tracking, self.times = replay(self.recording.samples, self.recording.mapping, fps=self.recording.fps)
        self.calibration: Calibration | None = None
        self.skeleton = sk.Skeleton.canonical()
        if calibrate_s > 0:
            n = calibration_window(self.times, calibrate_s)
            self.calibration = calibrate([tracking.frame(i) for i in range(n)])
            tracking, _ = replay(
                self.recording.samples, self.recording.mapping, self.calibration, fps=self.recording.fps
            )
            self.skeleton = self.calibration.skeleton
        self.tracking = tracking

    @property
    def fps(self) -> float:
        return self.tracking.fps

    @property
    def num_frames(self) -> int:
        return len(self.tracking)

    def frame(self, frame: int) -> SensorFrame:
        f = self.tracking.frame(int(np.clip(frame, 0, len(self.tracking) - 1)))
        return apply_edits(f.readings, self.sensors, frame)
