"""A tracker recording as the studio's sensor source: it opens like a clip, with the
timeline, and has no ground truth (``ground_truth`` is NaN)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from engine import skeleton as sk
from engine.methods import SensorFrame
from engine.sources.calibration import Calibration, calibrate
from engine.sources.live import calibration_window
from engine.sources.live_source import with_studio_edits
from engine.sources.recording import Recording, read_recording, replay


class RecordingSource:
    """Frames of a recording (:mod:`engine.sources.recording`), replayed as live.

    Parameters
    ----------
    recording : Recording or path
    calibrate_s : float
        Calibrate from the first ``calibrate_s`` seconds (0: none; the canonical
        skeleton is used). The calibration frames stay on the timeline.
    """

    live = False
    motion = None

    def __init__(self, recording: Recording | str | Path, calibrate_s: float = 0.0) -> None:
        self.recording = recording if isinstance(recording, Recording) else read_recording(recording)
        self.name = self.recording.path.stem if self.recording.path else "recording"
        tracking, self.times = replay(self.recording.samples, self.recording.mapping, fps=self.recording.fps)
        self.calibration: Calibration | None = None
        self.skeleton = sk.Skeleton.canonical()
        if calibrate_s > 0:
            n = calibration_window(self.times, calibrate_s)
            self.calibration = calibrate([tracking.frame(i) for i in range(n)])
            tracking, _ = replay(self.recording.samples, self.recording.mapping, self.calibration, fps=self.recording.fps)
            self.skeleton = self.calibration.skeleton
        self.tracking = tracking
        self.sensors: tuple = ()

    @property
    def fps(self) -> float:
        return self.tracking.fps

    @property
    def num_frames(self) -> int:
        return len(self.tracking)

    def set_sensors(self, sensors: tuple) -> None:
        self.sensors = tuple(sensors)

    def ground_truth(self, frame: int) -> np.ndarray:
        return np.full((sk.NUM_JOINTS, 3), np.nan)

    def frame(self, frame: int) -> SensorFrame:
        f = self.tracking.frame(int(np.clip(frame, 0, len(self.tracking) - 1)))
        return with_studio_edits(f.readings, self.sensors, frame)
