"""A live tracker stream as the studio's sensor source: a clip that grows as frames
arrive, with recording, a calibration countdown and a status for the status light.

The studio's engine thread reads it as a :class:`engine.sensor_source.SensorSource`;
this class keeps every received frame (up to ``history_s`` seconds) so the timeline can
scrub back through them, and ``live`` tells playback to follow the newest frame instead
of a clock. There is no ground truth: ``ground_truth`` is NaN.
"""

from __future__ import annotations

import threading
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from engine import skeleton as sk
from engine.sensor_source import SensorSource, apply_edits
from engine.sensors import SensorFrame
from engine.tracker_io.calibration import Calibration, calibrate
from engine.tracker_io.receiver import LiveFrame, VMCReceiver
from engine.tracker_io.recording import RecordingWriter, header
from engine.tracker_io.trackers import DEFAULT_TIMEOUT_S, TrackerMapping


@dataclass(frozen=True)
class LiveStatus:
    """What the status light shows (a snapshot; plain values).

    Attributes
    ----------
    address : str
        ``host:port`` listened on.
    packets, frames, malformed, duplicates, late : int
        Receiver counters (``malformed`` = packets + messages).
    packet_rate_hz : float
        Datagrams per second over the last few hundred.
    age_s : float or None
        Seconds since the newest frame arrived (None before the first).
    recording : str or None
        Path being recorded to.
    calibration_phase : str
        ``""``, ``"countdown"`` (get into the pose), ``"capturing"`` or ``"done"``.
    calibration_left_s : float
        Seconds left in the current phase.
    calibration : str
        Summary of the last calibration, or why it failed.
    """

    address: str
    packets: int
    frames: int
    malformed: int
    duplicates: int
    late: int
    packet_rate_hz: float
    age_s: float | None
    recording: str | None
    calibration_phase: str
    calibration_left_s: float
    calibration: str


#: Seconds past the end of a calibration's capture window after which, no frame having
#: finished it, it fails (the stream stopped or never started).
CALIBRATION_STALL_S = 1.0


class LiveSource(SensorSource):
    """Receive VMC on ``host:port`` and serve the frames to the studio.

    Parameters
    ----------
    host, port : str, int
    mapping : TrackerMapping, optional
    convention : str
        Axes of the incoming poses (VMC: ``unity``).
    fps : float
        Nominal stream rate, frames per second.
    history_s : float
        Seconds of frames kept for the timeline.
    """

    live = True

    def __init__(
        self,
        host: str = "0.0.0.0",
        port: int = 39539,
        mapping: TrackerMapping | None = None,
        convention: str = "unity",
        fps: float = sk.FPS,
        timeout_s: float = DEFAULT_TIMEOUT_S,
        history_s: float = 600.0,
    ) -> None:
        self.mapping = mapping or TrackerMapping()
        self.receiver = VMCReceiver(host, port, self.mapping, convention, timeout_s, on_frame=self._on_frame)
        self._fps = float(fps)
        self._max = max(int(history_s * fps), 1)
        self._frames: list[LiveFrame] = []
        self._offset = 0  # frames dropped from the front of the history
        self._lock = threading.Lock()
        self.skeleton = sk.Skeleton.canonical()
        #: Bumped whenever :attr:`skeleton` changes (the engine then resets its methods).
        self.skeleton_version = 0
        self.calibration: Calibration | None = None
        self._cal: dict[str, Any] = {"phase": "", "until": 0.0, "window": 0.0, "pose": "auto", "frames": [], "note": ""}
        self._recorder: RecordingWriter | None = None

    # -- lifecycle -----------------------------------------------------------------------

    def start(self) -> "LiveSource":
        self.receiver.start()
        return self

    def close(self) -> None:
        """Stop receiving and finish a recording in progress (the frames stay)."""
        if self.receiver.running:
            self.receiver.stop()
        self.stop_recording()

    # -- the sensor-source contract ---------------------------------------------------------

    @property
    def fps(self) -> float:
        return self._fps

    @property
    def num_frames(self) -> int:
        with self._lock:
            return self._offset + len(self._frames)

    def frame(self, frame: int) -> SensorFrame:
        """Readings at received frame ``frame`` (clamped to what is kept), restricted to
        the studio's enabled sensors when it has set any, with their DoF and offsets."""
        with self._lock:
            if not self._frames:
                return SensorFrame(frame, {})
            f = self._frames[int(np.clip(frame - self._offset, 0, len(self._frames) - 1))]
        return apply_edits(f.sensors.readings, self.sensors, frame)

    def arrival(self, frame: int) -> float | None:
        """``time.perf_counter()`` when ``frame`` arrived (for latency), if still kept."""
        with self._lock:
            k = frame - self._offset
            return self._frames[k].arrival if 0 <= k < len(self._frames) else None

    # -- recording -------------------------------------------------------------------------

    def start_recording(self, path: str | Path) -> None:
        """Record every sample from now on (atomically: the file appears on stop)."""
        self.stop_recording()
        rec = RecordingWriter(
            path, header(self._fps, self.mapping, f"vmc udp {self.receiver.host}:{self.receiver.port}")
        )
        self._recorder = rec
        self.receiver.recorder = rec

    @property
    def recording(self) -> bool:
        """Whether a recording is in progress."""
        return self._recorder is not None

    def stop_recording(self) -> Path | None:
        """Finish the recording in progress and return its file; None without one, or when
        no sample arrived (then no file is written: it cannot be opened again)."""
        rec, self._recorder = self._recorder, None
        self.receiver.recorder = None
        if rec is None:
            return None
        if rec.samples == 0:
            rec.abort()
            return None
        rec.close()
        return rec.path

    # -- calibration ----------------------------------------------------------------------

    def start_calibration(self, countdown_s: float = 3.0, window_s: float = 2.0, pose: str = "auto") -> None:
        """Count down ``countdown_s`` seconds (time to get into the pose), then average
        ``window_s`` seconds of frames and calibrate (:func:`calibrate`)."""
        now = time.perf_counter()
        with self._lock:
            self._cal = {
                "phase": "countdown",
                "until": now + countdown_s,
                "window": window_s,
                # frames move the calibration on; without them it fails at this time
                "deadline": now + countdown_s + window_s + CALIBRATION_STALL_S,
                "pose": pose,
                "frames": [],
                "note": "",
            }

    def _expired(self, now: float) -> bool:
        """With the lock held: fail a calibration whose frames stopped coming (or never
        came) before its capture ended, so that a later stream does not finish it unasked."""
        cal = self._cal
        if cal["phase"] not in ("countdown", "capturing") or now < cal.get("deadline", float("inf")):
            return False
        got = len(cal["frames"])
        why = "no tracker frame arrived" if not got else f"the trackers stopped after {got} frames"
        cal.update(phase="done", note=f"calibration failed: {why}; calibrate again", frames=[])
        return True

    def _on_frame(self, f: LiveFrame) -> None:
        with self._lock:
            self._frames.append(f)
            if len(self._frames) > self._max:
                drop = len(self._frames) - self._max
                del self._frames[:drop]
                self._offset += drop
            cal = self._cal
            now = time.perf_counter()
            if self._expired(now):
                return
            if cal["phase"] == "countdown" and now >= cal["until"]:
                cal.update(phase="capturing", until=now + cal["window"])
            if cal["phase"] != "capturing":
                return
            if self.calibration is None:
                cal["frames"].append(f.sensors)
            else:  # calibrate from the raw trackers, not the previous calibration's joints
                self.receiver.state.calibration = None
                cal["frames"].append(self.receiver.state.frame(f.index, f.t))
                self.receiver.state.calibration = self.calibration
            if now < cal["until"]:
                return
            try:
                result = calibrate(cal["frames"], cal["pose"])
            except Exception as exc:  # a failed calibration keeps the old one and says why
                cal.update(phase="done", note=f"calibration failed: {exc}", frames=[])
                return
            cal.update(phase="done", note=result.summary(), frames=[])
            self.calibration = result
            self.skeleton = result.skeleton
            self.skeleton_version += 1
        self.receiver.set_calibration(result)

    # -- status ---------------------------------------------------------------------------

    def status(self) -> LiveStatus:
        s = self.receiver.snapshot_stats()
        last = self.receiver.last_arrival
        with self._lock:
            cal = self._cal
            self._expired(time.perf_counter())
            left = max(0.0, cal["until"] - time.perf_counter()) if cal["phase"] in ("countdown", "capturing") else 0.0
            phase, note = cal["phase"], cal["note"]
        rec = self._recorder
        return LiveStatus(
            f"{self.receiver.host}:{self.receiver.port}",
            s.packets,
            s.frames,
            s.malformed_packets + s.malformed_messages,
            s.duplicates,
            s.late,
            s.packet_rate_hz,
            None if last is None else time.perf_counter() - last,
            str(rec.path) if rec is not None else None,
            phase,
            left,
            note,
        )
