"""The engine thread: commands in through a queue, immutable snapshots out.

:class:`EngineThread` is a plain :class:`threading.Thread` (no Qt), so it is tested
headless. It owns the reconstruction methods and the sensor source; the session sends
changes as :mod:`engine.studio.commands`. After each solved frame it publishes a
:class:`~engine.studio.snapshot.Snapshot` of plain, read-only numpy arrays: readers keep
the newest one (``thread.latest``) or get called back (``listeners``, on this thread).
Commands are dispatched on their class: each has one ``@cmd.handles`` method here.

Which frame is due when is the :class:`~engine.studio.playback.PlaybackClock`'s
arithmetic (two paces: solve every frame, or keep real time and skip); the methods are
a :class:`~engine.studio.method_set.MethodSet`. A method that raises or returns NaN
never kills the thread; the error is reported in the snapshot.
"""

from __future__ import annotations

import os
import queue
import sys
import threading
import time
from collections import deque
from collections.abc import Callable
from typing import Any

import numpy as np

from engine import skeleton as sk
from engine.joining import STOP_WAIT_S, join_saying
from engine.methods.base import DecodesLatents, FrameResult, Method
from engine.sensor_source import SensorSource
from engine.sensors import SensorFrame
from engine.startup_trace import mark
from engine.studio import commands as cmd
from engine.studio.clip_source import ClipSource
from engine.studio.decode import decode_request
from engine.studio.frame_figures import gizmos_of, losses_of, timing_of
from engine.studio.latent_debug import LatentDebug
from engine.studio.method_edits import make_method
from engine.studio.method_set import MethodSet
from engine.studio.playback import ENDED, LOOPED, PlaybackClock, is_jump
from engine.studio.snapshot import HISTORY, HistoryEntry, Snapshot, readonly

#: How often playback of a live source looks for a newer frame, seconds.
LIVE_POLL_S = 0.005

#: Problems a snapshot repeats (newest last), so a reader that skipped the snapshot
#: which first reported one still shows it.
RECENT_ERRORS = 5


class EngineThread(threading.Thread):
    """Runs the reconstruction off the GUI thread; see the module docstring.

    Parameters
    ----------
    method_factory : callable, optional
        ``factory(name) -> Method``; defaults to :func:`engine.studio.method_edits.make_method`.
    commands : queue, optional
        Where commands arrive (anything with ``put``, ``get(timeout=)`` and
        ``get_nowait()`` raising :class:`queue.Empty`, e.g. a ``multiprocessing`` queue
        when the loop runs in its own process, :mod:`engine.studio.process`); a new
        :class:`queue.Queue` by default.

    Attributes
    ----------
    failure : str
        Why the engine stopped for good, '' while it runs: always '' here, since a
        method's error is reported in the snapshot and never ends the thread (the
        engine process sets it when its child dies).
    """

    failure: str = ""

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

    # -- public API (any thread) --------------------------------------------------------
    def prepare(self, method: str) -> None:
        """Build ``method`` before the loop starts (:meth:`MethodSet.prepare`), from the starting thread."""
        self._methods.prepare(method)
        mark(f"engine: method {method} prepared")

    def submit(self, command: cmd.Command) -> None:
        """Queue a command; returns at once.

        Raises
        ------
        TypeError
            For a command no handler takes (:data:`engine.studio.commands.HANDLERS`).
        """
        cmd.check_command(command)
        self._queue.put(command)

    def stop(self, timeout: float = STOP_WAIT_S) -> None:
        """Finish the loop after the command or frame in hand (commands queued behind it
        are dropped) and join it for at most ``timeout`` seconds, saying on stderr what it
        waits for (:func:`engine.joining.join_saying`)."""
        self._stopping = True  # read between commands: a queue of inspections is not worked through
        self._queue.put(cmd.Stop())  # wakes a loop blocked on the queue
        join_saying(self, lambda: self.doing or "idle", timeout)

    # -- loop -----------------------------------------------------------------------
    def run(self) -> None:
        torch = sys.modules.get("torch")
        if torch is not None:  # leave a core to the GUI thread (and VTK) on small machines
            torch.set_num_threads(max(1, (os.cpu_count() or 2) - 1))
        while not self._stopping:
            self._drain(self._wait_time())
            if self._stopping:
                break
            if self._source is None or self._source.num_frames == 0:
                continue
            if self._source.skeleton_version != self._methods.skeleton_version:
                self._reset_methods()  # a live source was calibrated: a new skeleton
            was_playing = self._playing
            target = self._playback_frame() if self._playing else self._frame
            if target != self._last_solved or self._dirty:
                self._dirty = False
                self.doing = f"solving frame {target}"
                self._solve(target)
                self.doing = ""
            elif was_playing and not self._playing:
                self._republish()  # the end was reached on a solved frame: say playback stopped

    def _wait_time(self) -> float | None:
        """How long the queue may block: until the next frame is due, or forever."""
        if self._dirty:
            return 0.0
        if not self._playing or self._source is None:
            return None
        if self._source.live:
            return LIVE_POLL_S  # frames arrive on the network's schedule, not a clock's
        return self._clock.wait_time(self._frame, self._last_solved, self._source.fps)

    def _drain(self, timeout: float | None) -> None:
        try:
            c = self._queue.get(timeout=timeout) if timeout != 0.0 else self._queue.get_nowait()
        except queue.Empty:
            return
        while True:
            self._apply(c)
            if self._stopping:
                return
            try:
                c = self._queue.get_nowait()
            except queue.Empty:
                return

    def _apply(self, c: cmd.Command) -> None:
        handler = cmd.handler_for(type(c))
        if handler is None:  # reached the queue without submit(): said, and the loop goes on
            self._report_error(f"engine: no handler for command {type(c).__name__}")
            return
        was_dirty, self._dirty = self._dirty, True
        self.doing = type(c).__name__
        handler(self, c, was_dirty)
        self.doing = ""

    # -- command handlers: each takes the command and whether a solve was due before it
    @cmd.handles(cmd.Stop)
    def _on_stop(self, c: cmd.Stop, was_dirty: bool) -> None:
        self._stopping = True

    @cmd.handles(cmd.SetMotion, cmd.SetSource)
    def _on_set_source(self, c: cmd.SetMotion | cmd.SetSource, was_dirty: bool) -> None:
        self._opened = c.opened
        source = ClipSource(c.motion) if isinstance(c, cmd.SetMotion) else c.source
        try:
            source.set_sensors(self._methods.sensors)
        except Exception as exc:  # reported, and the old source stays
            self._report_error(f"sensor source: {exc}")
            return
        self._source = source
        self._frame, self._warnings, self._playing = 0, 0, False
        self._recent_errors.clear()
        self._reset_methods()

    @cmd.handles(cmd.SetSensors)
    def _on_set_sensors(self, c: cmd.SetSensors, was_dirty: bool) -> None:
        self._ghost_errors.clear()  # other sensors: a ghost may run now, or fail anew
        if self._source is not None:
            try:
                self._source.set_sensors(c.sensors)
            except Exception as exc:
                self._report_error(f"sensor source: {exc}")
        self._methods.set_sensors(c.sensors)

    @cmd.handles(cmd.SetConstraints)
    def _on_set_constraints(self, c: cmd.SetConstraints, was_dirty: bool) -> None:
        self._methods.set_constraints(c.constraints)

    @cmd.handles(cmd.SetSettings)
    def _on_set_settings(self, c: cmd.SetSettings, was_dirty: bool) -> None:
        self._methods.set_settings(c.values, c.replace)

    @cmd.handles(cmd.SetMethod)
    def _on_set_method(self, c: cmd.SetMethod, was_dirty: bool) -> None:
        self._opened = c.opened
        self._ghost_errors.clear()
        built = self._methods.select(c.name, c.ghosts)
        mark(f"engine: method {c.name} ready")
        if not built:
            # a method that cannot be built (e.g. a broken weights file) leaves the
            # session as it was; the window shows why
            self._method_error = self._pending_error
            return
        self._reset_methods()

    @cmd.handles(cmd.Seek)
    def _on_seek(self, c: cmd.Seek, was_dirty: bool) -> None:
        self._frame = self._clamp(c.frame)
        self._clock.restart(self._frame)
        self._decoded = None

    @cmd.handles(cmd.Step)
    def _on_step(self, c: cmd.Step, was_dirty: bool) -> None:
        self._playing = False
        self._frame = self._clamp(self._frame + c.delta)

    @cmd.handles(cmd.Play)
    def _on_play(self, c: cmd.Play, was_dirty: bool) -> None:
        self._plays += 1
        self._playing = True
        self._clock = PlaybackClock(c.speed, c.loop, c.pace, (time.monotonic(), self._frame))
        self._decoded = None
        self._dirty = was_dirty or self._frame != self._last_solved

    @cmd.handles(cmd.Pause)
    def _on_pause(self, c: cmd.Pause, was_dirty: bool) -> None:
        # say so without solving the frame again (which would move temporal state on)
        self._playing, self._dirty = False, was_dirty
        self._republish()

    @cmd.handles(cmd.InspectLatent)
    def _on_inspect_latent(self, c: cmd.InspectLatent, was_dirty: bool) -> None:
        # the frame on screen, not solved again
        self._dirty = False
        error = self._latent.inspect(self._methods.method, c.joint, lambda: self._stopping)
        if error and not self._stopping:
            self._report_error(f"inspect latent: {error}")
        self._republish()

    @cmd.handles(cmd.DecodeLatent)
    def _on_decode_latent(self, c: cmd.DecodeLatent, was_dirty: bool) -> None:
        # debug mode: decode and show, without solving the frame again (which would
        # move the method's temporal state on)
        self._dirty = False
        self._decode(c.latent)
        self._republish()

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

    def _clamp(self, frame: int) -> int:
        n = self._source.num_frames if self._source is not None else 0
        return int(np.clip(frame, 0, max(n - 1, 0)))

    def _playback_frame(self) -> int:
        """The frame playback is at now (:meth:`PlaybackClock.advance`); a live source's
        newest frame, whatever the pace."""
        src = self._loaded()
        if src.live:
            self._frame = max(src.num_frames - 1, 0)
            return self._frame
        f, event = self._clock.advance(self._frame, self._last_solved, src.num_frames, src.fps)
        if event == LOOPED:
            self._reset_methods()
        elif event == ENDED:
            self._playing = False
        self._frame = f
        return f

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
            gizmos=gizmos_of(self._methods.constraints, self._last_pose, self._report_error),
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
