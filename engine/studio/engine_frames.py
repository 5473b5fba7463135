"""The engine thread's state and its work on one frame: solve it, keep it, publish it.

:class:`EngineFrames` is the base of :class:`engine.studio.thread.EngineThread`, which adds
the loop and the commands. It builds the thread's state; :meth:`~EngineFrames._solve`
steps the method and the ghosts on a frame of the source (a method that raises or returns
NaN is reported, never fatal), keeps the frame's history entry, and
:meth:`~EngineFrames._publish` hands readers a :class:`~engine.studio.snapshot.Snapshot`
of plain, read-only numpy arrays (``latest`` and ``listeners``).
"""

from __future__ import annotations

import queue
import threading
import time
from collections import deque
from collections.abc import Callable
from typing import Any

import numpy as np

from engine import skeleton as sk
from engine.methods.base import Configurable, DecodesLatents, FrameResult, Method
from engine.sensor_source import SensorSource
from engine.sensors import SensorFrame
from engine.startup_trace import mark
from engine.studio.decode import decode_request
from engine.studio.frame_figures import gizmos_of, losses_of, timing_of
from engine.studio.latent_debug import LatentDebug
from engine.studio.method_edits import make_method
from engine.studio.method_set import MethodSet
from engine.studio.playback import PlaybackClock, is_jump
from engine.studio.snapshot import HISTORY, HistoryEntry, Snapshot, readonly

#: Problems a snapshot repeats (newest last), so a reader that skipped the snapshot
#: which first reported one still shows it.
RECENT_ERRORS = 5


class EngineFrames(threading.Thread):
    """The engine thread's state and frame work; constructed as
    :class:`~engine.studio.thread.EngineThread` (its parameters)."""

    def __init__(self, method_factory: Callable[[str], Method] | None = None, commands: Any = None) -> None:
        super().__init__(name="dragposer-engine", daemon=True)
        self._queue: Any = queue.Queue() if commands is None else commands
        self._factory = method_factory or make_method
        # looked up at each build, so a factory swapped on a running engine takes effect
        self._methods = MethodSet(lambda name: self._factory(name), self._report_error)
        self.latest: Snapshot | None = None
        self.listeners: list[Callable[[Snapshot], None]] = []
        self._source: SensorSource | None = None
        self._frame, self._last_solved = 0, -2
        self._playing = False
        self._clock = PlaybackClock()
        self._dirty = False
        self._seq = self._solved = self._skipped = self._warnings = self._plays = 0
        self._fps = self._last_ms = 0.0
        self._last_pose = np.zeros((sk.NUM_JOINTS, 3))
        self._last_result: FrameResult | None = None
        self._decoded: np.ndarray | None = None
        self._last_ghosts: dict[str, np.ndarray] = {}
        self._history: deque[HistoryEntry] = deque(maxlen=HISTORY)
        self._history_run = 0
        self._pending_error = self._method_error = ""
        self._recent_errors: deque[str] = deque(maxlen=RECENT_ERRORS)
        self._ghost_errors: dict[str, str] = {}  # ghost -> the failure last reported
        self._stopping = False
        self.doing = ""  # the command or frame in hand, said by a stop that waits for it
        self._latency_ms: float | None = None  # a live frame's arrival to its solve, ms
        self._latent = LatentDebug()
        self._opened = 0  # the ``opened`` of the newest SetMotion, SetSource or SetMethod

    def _republish(self) -> None:
        """Publish the last solved frame again with the current playback state and debug pose."""
        if self._source is not None and self._last_solved >= 0:
            self._publish(
                self._last_solved,
                self._source.frame(self._last_solved),
                self._last_result,
                self._last_ms,
                self._pending_error,
                self._last_ghosts,
            )

    # -- methods --------------------------------------------------------------------
    def _reset_methods(self) -> None:
        self._methods.reset(self._source)
        self._last_solved = -2  # nothing solved since: the next solve starts clean

    def _report_error(self, message: str) -> None:
        self._warnings += 1
        self._pending_error = message
        self._recent_errors.append(message)

    def _loaded(self) -> SensorSource:
        """The source, which playing, solving and publishing a frame need (set first)."""
        assert self._source is not None, "no source loaded"
        return self._source

    def _solve(self, frame: int) -> None:
        src = self._loaded()
        jump = is_jump(frame, self._last_solved, src.fps)
        # an edit while paused solves the frame again from the state before the first edit
        self._methods.keep_state(not self._playing and not jump and frame == self._last_solved)
        if jump:
            if self._last_solved >= 0:  # after a load, loop or method change it is done already
                self._reset_methods()  # temporal state is meaningless across a jump
            self._history.clear()
            self._history_run += 1
        elif self._playing and frame > self._last_solved + 1:
            self._skipped += frame - self._last_solved - 1
        sf = src.frame(frame)
        error = self._pending_error
        self._pending_error = ""
        t0 = time.perf_counter()
        res = None
        if self._methods.method is not None:
            try:
                res = self._methods.step(self._methods.method, sf)
                self._last_pose, self._last_result = res.positions, res
                self._warnings += len(res.warnings)
            except Exception as exc:  # never let a method kill the engine thread
                error = f"{self._methods.name} at frame {frame}: {type(exc).__name__}: {exc}"
                self._warnings += 1
                self._recent_errors.append(error)
                self._reset_methods()
        ms = (time.perf_counter() - t0) * 1000.0
        arrived = src.arrival(frame)
        self._latency_ms = None if arrived is None else (time.perf_counter() - arrived) * 1000.0
        ghosts = {}
        for name, m in self._methods.ghosts.items():
            try:
                ghosts[name] = self._methods.step(m, sf).positions
                self._ghost_errors.pop(name, None)
            except Exception as exc:  # said once per ghost and cause, not on every frame
                if self._ghost_errors.get(name) != str(exc):
                    self._ghost_errors[name] = str(exc)
                    error = error or f"{name} at frame {frame}: {exc}"
                    self._recent_errors.append(f"{name} at frame {frame}: {exc}")
                    self._warnings += 1
        dt = max(ms / 1000.0, 1e-4)
        self._fps = 1.0 / dt if self._fps == 0 else 0.9 * self._fps + 0.1 / dt
        self._last_solved = frame
        self._solved += 1
        if jump and self._playing:  # the first solve after a reset is slow: time from here
            self._clock.restart(frame)
        self._last_ghosts, self._last_ms = ghosts, ms
        if res is not None:
            final = dict(res.losses[-1]) if res.losses else dict(losses_of(res, sf)[-1])
            latent = readonly(res.latent) if res.latent is not None else None
            view = self._latent.after_solve(self._methods.method, frame, res.latent)
            readouts = view.readouts() if view is not None else {}
            self._history.append(HistoryEntry(frame, res.iterations, ms, final, latent, readouts))
        self._publish(frame, sf, res, ms, error, ghosts)
        if self._solved == 1:
            mark("engine: first frame solved")
        # the pose is out: work the methods deferred (DragPoser's predictor pieces) now,
        # not inside the next frame's solve
        self._methods.between_frames()

    def _decode(self, latent: np.ndarray) -> None:
        if isinstance(self._methods.method, DecodesLatents):
            self._playing = False  # the decoded pose is shown on a paused frame
        shown = self._last_result.latent if self._last_result is not None else None
        decoded, error = decode_request(self._methods.method, self._methods.name, latent, shown, self._last_pose)
        if error:
            self._report_error(error)
        else:
            self._decoded = decoded

    def _publish(
        self, frame: int, sf: SensorFrame, res: FrameResult | None, ms: float, error: str, ghosts: dict[str, np.ndarray]
    ) -> None:
        src = self._loaded()
        joints = tuple(sf.readings)
        readings = [sf.readings[j] for j in joints]
        last = res or self._last_result
        self._seq += 1
        method = self._methods.method
        snap = Snapshot(
            seq=self._seq,
            frame=frame,
            num_frames=src.num_frames,
            positions=readonly(self._last_pose),
            ground_truth=readonly(src.ground_truth(frame)),
            ghosts={k: readonly(v) for k, v in ghosts.items()},
            target_joints=joints,
            target_positions=readonly(np.array([r.position for r in readings]).reshape(-1, 3)),
            target_rotations=readonly(np.array([r.rotation for r in readings]).reshape(-1, 4)),
            target_connected=readonly(np.array([r.connected for r in readings], bool)),
            gizmos=gizmos_of(self._methods.constraints, self._last_pose, self._report_error, frame),
            losses=losses_of(res, sf),
            latent=readonly(last.latent) if last is not None and last.latent is not None else None,
            iterations=res.iterations if res else 0,
            ms=ms,
            warnings=self._warnings,
            messages=tuple(res.warnings) if res else (),
            error=error,
            method_error=self._method_error,
            engine_fps=self._fps,
            playing=self._playing,
            method=method.name if method is not None else self._methods.name,
            can_decode=isinstance(method, DecodesLatents),
            configurable=method is None or isinstance(method, Configurable),
            decoded=readonly(self._decoded) if self._decoded is not None else None,
            history=tuple(self._history),
            history_run=self._history_run,
            opened=self._opened,
            solved=self._solved,
            frames_skipped=self._skipped,
            pace=self._clock.pace,
            timing=timing_of(res, ms, self._latency_ms),
            recent_errors=tuple(self._recent_errors),
            plays=self._plays,
            latent_view=self._latent.view,
            latent_detail=self._latent.detail,
            latent_note=self._latent.note,
        )
        self._method_error = ""
        self.latest = snap
        for cb in list(self.listeners):
            cb(snap)
