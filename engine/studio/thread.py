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
never kills the thread; the error is reported in the snapshot. The thread's state, a
frame's solve and its snapshot are the base's (:class:`~engine.studio.engine_frames.EngineFrames`);
this module adds the loop and the commands.
"""

from __future__ import annotations

import os
import queue
import sys
import time

import numpy as np

from engine.joining import STOP_WAIT_S, join_saying
from engine.startup_trace import mark
from engine.studio import commands as cmd
from engine.studio.clip_source import ClipSource
from engine.studio.engine_frames import EngineFrames
from engine.studio.playback import ENDED, LOOPED, PlaybackClock

#: How often playback of a live source looks for a newer frame, seconds.
LIVE_POLL_S = 0.005


class EngineThread(EngineFrames):
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
        self._fps = 0.0  # the rate of this method's solves, not an average with the last one's
        self._reset_methods()

    @cmd.handles(cmd.SetGhosts)
    def _on_set_ghosts(self, c: cmd.SetGhosts, was_dirty: bool) -> None:
        self._ghost_errors.clear()
        self._methods.set_ghosts(c.ghosts, self._source)

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
