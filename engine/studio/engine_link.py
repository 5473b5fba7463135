"""The session's state and its link to the engine: every change becomes a command.

:class:`EngineLink` is the base of :class:`engine.studio.session.Session`, which adds the
edits. It builds the session's state, starts, restarts and stops the engine (a thread of
this process or a child process), syncs a new engine with the whole session
(:meth:`~EngineLink.attach`) and sends it each change as a command
(:mod:`engine.studio.commands`), the sensor set's and the constraint list's included,
which it re-emits as ``events.sensors`` and ``events.constraints``.
"""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

from engine.editing.constraint_list import ConstraintList
from engine.motion.clip import Motion
from engine.sensor_source import SensorSource
from engine.solver.settings_edit import SettingsEdit
from engine.studio import commands as cmd
from engine.studio import events as ev
from engine.studio.process import EngineProcess
from engine.studio.scenes import default_settings
from engine.studio.session_sensors import SensorSet
from engine.studio.snapshot import Snapshot
from engine.studio.thread import EngineThread


class EngineLink:
    """The session's state and its engine; constructed as
    :class:`~engine.studio.session.Session` (its attributes)."""

    def __init__(self, method: str = "ik") -> None:
        self.events = ev.SessionEvents()
        self.motion: Motion | None = None
        self.path: Path | None = None
        self.rig_map: Path | None = None  # the joint mapping file ``path`` was opened with
        self.source: SensorSource | None = None  # a tracker recording or live stream instead of a clip
        self.sensors = SensorSet()
        self.constraints = ConstraintList()
        self.sensors.events.changed.connect(self._sensors_changed)
        self.constraints.events.changed.connect(self._constraints_changed)
        self.settings: SettingsEdit = default_settings()
        self.method = method
        #: Clips, sources and methods opened so far (``opened`` of their commands).
        self.opened = 0
        #: The ``opened`` of the clip or source now open: a snapshot below it was solved
        #: on the one before (a method switch does not count: its view stays until the
        #: new method's first solve).
        self.clip_opened = 0
        self.ghosts: tuple[str, ...] = ()
        self.frame = 0
        self.playing = False
        self.speed = 1.0
        self.loop = True
        self.pace = "every_frame"
        self.engine: EngineThread | EngineProcess | None = None
        self._sink: Callable[[Any], None] | None = None
        self._factory: Callable[[str], Any] | None = None
        #: Play commands sent to the engine; a snapshot saying "stopped" counts only when
        #: its ``plays`` is this (an older one predates the latest play request).
        self.plays = 0
        #: Paused while playing, and the engine's frame not yet taken: the engine solves a
        #: few frames past the timeline's last update before the pause reaches it, and the
        #: frame it stops on is the one its snapshot (the 3D view, the readouts) shows.
        self.pause_pending = False

    # -- engine ------------------------------------------------------------------------
    def start_engine(
        self,
        method_factory: Callable[[str], Any] | None = None,
        process: bool = False,
        started: EngineProcess | None = None,
    ) -> EngineThread | EngineProcess:
        """Start the engine and send it the whole session: a thread of this process, or
        with ``process`` a child process (:mod:`engine.studio.process`; the solver and
        the window then never wait for each other's interpreter lock). ``started`` is an
        engine process already running (started before the window's imports, so that its
        own imports and model loading run beside them), taken as it is."""
        self._factory = method_factory
        if started is not None:
            self.engine = started
        else:
            self.engine = EngineProcess(method_factory) if process else EngineThread(method_factory)
            self.engine.start()
        self.attach(self.engine.submit)
        return self.engine

    def _engine_in_thread(self) -> None:
        """Move the engine from its process into a thread of this one (for a source that
        cannot leave this process, such as a live tracker stream); the whole session is
        sent to the new engine."""
        old = self.engine
        self.engine = EngineThread(self._factory)
        self.engine.start()
        if old is not None:
            old.stop()
        self.attach(self.engine.submit)

    def restart_engine(self) -> EngineThread | EngineProcess:
        """Replace an engine that died by a new one of the same kind (a process, or a
        thread) and send it the whole session: clip or source, method and ghosts,
        settings, sensors, constraints, frame and playback, so no edit made meanwhile is
        lost (:mod:`engine.studio.restarts` decides whether to)."""
        old = self.engine
        process = isinstance(old, EngineProcess)
        if process and self.source is not None and not EngineProcess.can_send(cmd.SetSource(self.source)):
            process = False  # a live source stays in this process
        self.engine = EngineProcess(self._factory) if process else EngineThread(self._factory)
        self.engine.start()
        if old is not None:
            old.stop(timeout=0.5)  # already dead: frees its pipe and queue
        self.attach(self.engine.submit)
        return self.engine

    def shutdown(self) -> None:
        """Stop the engine thread (if any) and wait for it; close a live source."""
        if self.engine is not None:
            self.engine.stop()
        self._sink = None
        self._close_source()

    @property
    def latest(self) -> Snapshot | None:
        """The engine's newest snapshot (None before the first solve or without engine)."""
        return None if self.engine is None else self.engine.latest

    def attach(self, sink: Callable[[Any], None] | None) -> None:
        """Send every change to ``sink`` (an engine's ``submit``) and sync it now."""
        self._sink = sink
        if sink is None:
            return
        sink(cmd.SetMethod(self.method, self.ghosts, self.opened))
        sink(cmd.SetSettings(self.settings))
        sink(cmd.SetSensors(tuple(self.sensors.values())))
        if self.motion is not None:
            sink(cmd.SetMotion(self.motion, self.opened))
        elif self.source is not None:
            sink(cmd.SetSource(self.source, self.opened))
        sink(cmd.SetConstraints(tuple(self.constraints)))
        sink(cmd.Seek(self.frame))
        self.plays = 0  # a new engine has seen none
        if self.playing:
            self._send_play()

    def _send(self, command: Any) -> None:
        if self._sink is not None:
            self._sink(command)

    def decode_latent(self, latent: np.ndarray) -> None:
        """Show the pose the method's decoder makes of ``latent`` (L,) (debug mode)."""
        self._send(cmd.DecodeLatent(np.asarray(latent, float).copy()))

    def inspect_latent(self, joint: str = "") -> None:
        """Ask for the frame's term forces, dimension sweep and ``joint``'s influences (snapshot ``latent_detail``)."""
        self._send(cmd.InspectLatent(str(joint)))

    def _sensors_changed(self, e: ev.SensorsChanged) -> None:
        self._send(cmd.SetSensors(e.sensors))
        self.events.sensors.emit(e)

    def _constraints_changed(self, e: ev.ConstraintsChanged) -> None:
        self._send(cmd.SetConstraints(e.constraints))
        self.events.constraints.emit(e)

    def _close_source(self) -> None:
        source, self.source = self.source, None
        if source is not None:
            source.close()

    def _send_play(self) -> None:
        self.plays += 1
        self._send(cmd.Play(self.speed, self.loop, self.pace))
