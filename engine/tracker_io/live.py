"""Realtime reconstruction from a live tracker stream, and its figures.

:class:`LiveRun` takes the newest frame from a :class:`~engine.tracker_io.receiver.VMCReceiver`,
hands its :class:`~engine.methods.SensorFrame` to a reconstruction method (exactly what
the method gets from simulated trackers) and times each solve from the arrival of the
frame's packet to the solved pose. A solver slower than the stream skips to the newest
frame; skipped frames are counted. An optional first window calibrates the wearer
(:mod:`engine.tracker_io.calibration`) before solving starts.

Real-time policy: with a frame budget, each frame's solve gets the deadline ``arrival +
budget`` (methods with :attr:`~engine.methods.Method.takes_deadline`: DragPoser stops
iterating when one more iteration would end past it, at least one iteration per frame),
and the work that can wait (DragPoser's temporal predictor) runs after the pose is out,
while the loop waits for the next frame. A frame that starts late, because that work or
the previous solve ran long, gets fewer iterations instead of making the next frames
late too.
"""

from __future__ import annotations

import gc
import threading
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field

import numpy as np

from engine import skeleton as sk
from engine.methods import FrameResult, Method, SensorFrame, driver
from engine.motion.clip import Motion
from engine.tracker_io.calibration import Calibration, calibrate
from engine.tracker_io.live_figures import FrameFigures
from engine.tracker_io.receiver import VMCReceiver


@dataclass
class LiveResult:
    """What a live run produced.

    Attributes
    ----------
    times : list of float
        Stream time of every solved frame, seconds.
    results : list of FrameResult
    sensors : list of SensorFrame
        The readings each solved frame was given. The three are kept only when the run
        keeps frames (:class:`LiveRun`'s ``keep_frames``: to write the motion or compare
        it with a reference); a stream of an hour would otherwise hold 200,000 poses.
    figures : FrameFigures
        Latency (packet arrival to solved pose), the method's time, iterations and
        fresh devices of the newest frames, and their summaries over the whole run, in
        memory that does not grow with the run (:mod:`engine.tracker_io.live_figures`).
    tracker_error_sum_m, tracker_error_count : float, int
        Sum and count of the distances from each connected tracker to its joint in the
        solved pose, metres (:meth:`tracker_error_cm`), kept as the frames are solved.
    frames_received : int
        Frames that arrived after calibration (the ones the solver was offered).
    frames_skipped : int
        Of those, frames superseded by a newer one while the solver was busy.
    frames_skipped_first_solve : int
        Of those, frames that arrived during the first solve (DragPoser solves its first
        frame in offline mode, to convergence: a start-up cost, not a steady one).
    calibration : Calibration or None
    calibration_frames : int
        Frames spent calibrating.
    """

    times: list[float] = field(default_factory=list)
    results: list[FrameResult] = field(default_factory=list)
    sensors: list[SensorFrame] = field(default_factory=list)
    figures: FrameFigures = field(default_factory=FrameFigures)
    frames_received: int = 0
    frames_skipped: int = 0
    frames_skipped_first_solve: int = 0
    calibration: Calibration | None = None
    calibration_frames: int = 0
    tracker_error_sum_m: float = 0.0
    tracker_error_count: int = 0

    @property
    def frames_solved(self) -> int:
        return self.figures.frames

    def tracker_error_cm(self) -> float | None:
        """Mean distance, cm, from each connected tracker to its joint in the solved
        pose, over every solved frame (None before any)."""
        return 100.0 * self.tracker_error_sum_m / self.tracker_error_count if self.tracker_error_count else None

    def add_tracker_error(self, res: FrameResult, f: SensorFrame) -> None:
        for j, r in f.connected().items():
            self.tracker_error_sum_m += float(np.linalg.norm(res.positions[sk.JOINT_INDEX[j]] - r.position))
            self.tracker_error_count += 1


class LiveRun:
    """Solve a live stream frame by frame.

    Parameters
    ----------
    receiver : VMCReceiver
        Started by the caller.
    method : Method
        Reset here with ``skeleton`` (or the calibrated one).
    skeleton : Skeleton
        The wearer's skeleton when not calibrating.
    fps : float
        Nominal stream rate (the method's frame rate).
    calibrate_s : float
        Seconds of stream (by stream time) to calibrate from first; 0: no calibration.
    calibration_pose : str
        ``auto``, ``tpose`` or ``standing``.
    budget_ms : float
        Per-frame budget from the frame's arrival to its solved pose, milliseconds
        (module doc); 0: none, every frame gets all its iterations.
    keep_frames : bool
        Keep every solved frame's result and readings (:class:`LiveResult`); False keeps
        only the figures, so a long stream does not grow the process.
    """

    def __init__(
        self,
        receiver: VMCReceiver,
        method: Method,
        skeleton: sk.Skeleton,
        fps: float = sk.FPS,
        calibrate_s: float = 0.0,
        calibration_pose: str = "auto",
        budget_ms: float = 0.0,
        keep_frames: bool = True,
    ) -> None:
        self.receiver = receiver
        self.method = method
        self.skeleton = skeleton
        self.fps = fps
        self.calibrate_s = calibrate_s
        self.calibration_pose = calibration_pose
        self.budget_s = budget_ms / 1000.0
        self.keep_frames = keep_frames
        self.stop_event = threading.Event()
        self.result = LiveResult()  # filled while running, so an interrupt keeps it

    def run(
        self,
        duration_s: float | None = None,
        idle_timeout_s: float | None = None,
        on_frame: Callable[[LiveResult], None] | None = None,
    ) -> LiveResult:
        """Run until ``duration_s`` (wall clock from the call), until no frame came for
        ``idle_timeout_s`` after the stream started, or until :attr:`stop_event` is set."""
        out = self.result = LiveResult()
        if self.calibrate_s <= 0:
            driver.reset(self.method, self.skeleton, self.fps)  # live trackers: no ground truth
        start = time.perf_counter()
        # Python's automatic full collections walk every object, the growing per-frame
        # results included, and stalled a frame by 220-240 ms in two of three idle runs
        # (12 frames skipped; docs/trackers.md). During the stream only the young
        # generations are collected, between frames; full collections wait for the end.
        automatic_gc = gc.isenabled()
        gc.disable()
        try:
            self._loop(out, start, duration_s, idle_timeout_s, on_frame)
        finally:
            if automatic_gc:
                gc.enable()
        return out

    def _loop(
        self,
        out: LiveResult,
        start: float,
        duration_s: float | None,
        idle_timeout_s: float | None,
        on_frame: Callable[[LiveResult], None] | None,
    ) -> None:
        window: list[SensorFrame] = []
        cal_t0: float | None = None
        calibrating = self.calibrate_s > 0
        last_index = 0
        while not self.stop_event.is_set():
            now = time.perf_counter()
            if duration_s is not None and now - start >= duration_s:
                break
            f = self.receiver.wait_frame(last_index, timeout=0.1)
            if f is None:
                # idle = nothing new arrived for a while (a slow solve is not idleness)
                last = self.receiver.last_arrival
                if idle_timeout_s is not None and last is not None and time.perf_counter() - last >= idle_timeout_s:
                    break
                continue
            missed = f.index - last_index - 1
            last_index = f.index
            if calibrating:
                cal_t0 = f.t if cal_t0 is None else cal_t0
                out.calibration_frames += 1 + missed
                window.append(f.sensors)
                if f.t - cal_t0 < self.calibrate_s:
                    continue
                # the window ends with the first frame at or past calibrate_s seconds
                # (``calibration_window`` says the same for recordings)
                out.calibration = calibrate(window, self.calibration_pose)
                self.receiver.set_calibration(out.calibration)
                driver.reset(self.method, out.calibration.skeleton, self.fps)
                calibrating = False
                continue
            out.frames_received += 1 + missed
            out.frames_skipped += missed
            if out.frames_solved == 1:
                out.frames_skipped_first_solve = missed
            res = driver.step(self.method, f.sensors, f.arrival + self.budget_s if self.budget_s > 0 else None)
            latency_ms = 1000.0 * (time.perf_counter() - f.arrival)
            out.figures.add(latency_ms, res.ms, res.iterations, f.fresh, f.devices)
            out.add_tracker_error(res, f.sensors)
            if self.keep_frames:
                out.times.append(f.t)
                out.results.append(res)
                out.sensors.append(f.sensors)
            if on_frame is not None:
                on_frame(out)
            self.method.between_frames()  # the pose is out: deferred work now
            gc.collect(1)  # young generations only (see run)


def calibration_window(times: Sequence[float] | np.ndarray, seconds: float) -> int:
    """Frames a calibration of ``seconds`` takes from a stream with these frame times:
    every frame less than ``seconds`` after the first, and the one that completes them."""
    t = np.asarray(times, float)
    if t.size == 0:
        return 0
    return min(int(np.searchsorted(t - t[0], seconds, side="left")) + 1, t.size)


def to_motion(
    times: Sequence[float] | np.ndarray,
    results: Sequence[FrameResult],
    skeleton: sk.Skeleton,
    fps: float,
    name: str = "",
) -> Motion:
    """The solved frames on a regular timeline at ``fps`` from the first to the last
    solved time; a frame that was not solved holds the pose solved before it."""
    if not results:
        return Motion(np.zeros((0, sk.NUM_JOINTS, 4)), np.zeros((0, 3)), skeleton, fps, name)
    t = np.asarray(times, float)
    slots = np.round((t - t[0]) * fps).astype(int)
    n = int(slots.max()) + 1
    pick = np.full(n, -1)
    pick[slots] = np.arange(len(slots))
    pick = np.maximum.accumulate(pick)
    local = np.stack([r.local_rot for r in results])[pick]
    root = np.stack([r.root_pos for r in results])[pick]
    return Motion(local, root, skeleton, fps, name)


def reference_error(
    times: Sequence[float] | np.ndarray, results: Sequence[FrameResult], reference: Motion | None
) -> dict:
    """Mean joint position error (22 joints, cm) of solved frames against the clip
    frame at the same time (``round(t * fps)``), or a note that there is no ground truth."""
    if reference is None:
        return {"pos_cm": None, "note": "no ground truth: live trackers (give --reference CLIP.bvh to compare)"}
    from engine.metrics import position_error_cm

    gt = reference.positions()
    idx = np.round(np.asarray(times, float) * reference.fps).astype(int)
    keep = [k for k, i in enumerate(idx) if 0 <= i < len(gt)]
    if not keep:
        return {"pos_cm": None, "note": "no solved frame falls inside the reference clip's time range"}
    rec = np.stack([results[k].positions for k in keep])
    err = position_error_cm(gt[idx[keep]], rec)
    return {"pos_cm": float(np.mean(err)), "frames_compared": len(keep)}


def tracker_error_cm(results: Sequence[FrameResult], frames: Sequence[SensorFrame]) -> float | None:
    """Mean distance, cm, from each connected tracker to its joint in the solved pose
    (needs no ground truth)."""
    errs = []
    for res, f in zip(results, frames):
        for j, r in f.connected().items():
            errs.append(np.linalg.norm(res.positions[sk.JOINT_INDEX[j]] - r.position))
    return 100.0 * float(np.mean(errs)) if errs else None


def default_budget_ms(fps: float) -> float:
    """The live frame budget when none is given: 60 % of the frame period (10 ms at
    60 fps), which leaves the rest of the period for the work before and after the
    solve, a piece of the predictor between frames and the receiver thread. With fresh
    Adam moments under a deadline two iterations already give the offline accuracy
    (docs/trackers.md: idle, 10 ms gave 97.8 % solved, p95 14.3 ms, error equal to
    offline; 13.3 ms gave 96.8 %, p95 23.7 ms)."""
    return 0.6 * 1000.0 / fps
