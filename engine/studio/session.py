"""The studio's Qt-free model: the clip, sensors, constraints, settings and playback.

A :class:`Session` lives on the GUI thread. Views read its attributes and change it only
through its methods; every change fires one typed event on :attr:`Session.events`
(:mod:`engine.studio.events`) and, with an engine attached, becomes a command for the
engine thread (:mod:`engine.studio.commands`). The engine thread never touches the
session: commands carry frozen sensors and constraint objects the session never edits
after publishing them (an edit replaces the object), so the engine uses the session's
own constraints, without copies and without a lock.

The window never builds engine objects: it calls :meth:`Session.start_engine`, reads
:attr:`Session.latest` and edits through these methods. The sensor set and the
constraint list are sub-models with their own events, ``session.sensors``
(:mod:`engine.studio.session_sensors`) and ``session.constraints``
(:mod:`engine.editing.constraint_list`); the session sends each of their changes to
the engine and re-emits it as ``events.sensors`` or ``events.constraints``. The session's
state, its engine and the sending of changes are the base's
(:class:`~engine.studio.engine_link.EngineLink`); this module adds the edits.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from engine.constraints.base import Constraint
from engine.errors import UserError
from engine.methods import available_methods
from engine.motion.clip import Motion
from engine.sensor_source import SensorSource
from engine.sensors import Sensor
from engine.solver.settings_edit import SettingsEdit
from engine.studio import commands as cmd
from engine.studio import events as ev
from engine.studio.clips import load_clip, sensor_presets, tracked_position
from engine.studio.engine_link import EngineLink
from engine.studio.process import EngineProcess
from engine.studio.scenes import apply_scene, scene_to_dict

if TYPE_CHECKING:
    from engine.tracker_io.live_source import LiveSource
    from engine.tracker_io.recording_source import RecordingSource


class Session(EngineLink):
    """Everything the studio shows and edits; see the module docstring.

    Attributes
    ----------
    events : SessionEvents
        Typed signals: ``motion``, ``sensors``, ``constraints``, ``settings``, ``method``,
        ``frame``, ``playback``.
    motion : Motion or None
        Ground-truth clip the sensors are simulated from; ``path`` its file.
    sensors : SensorSet
        Active trackers by joint, in preset order (a read-only mapping), with their
        edits and ``sensors.events``; ``preset`` names the set ("" = custom).
    constraints : ConstraintList
        User constraints, in order (a read-only sequence), with their edits and
        ``constraints.events``.
    settings : SettingsEdit
        Optimizer parameters by name (``mode``, ``iterations``, ``lr``...).
    method : str
        Reconstruction method; ``ghosts`` are other methods drawn alongside it.
    frame : int
        Current frame (the engine's while playing, mirrored by :meth:`note_frame`).
    playing, speed, loop, pace
        Playback state; ``pace`` is ``"every_frame"`` or ``"real_time"``.
    """

    # -- sensors and constraints -----------------------------------------------------
    @property
    def preset(self) -> str:
        """The sensor preset (``sensors.preset``; "" for a custom set)."""
        return self.sensors.preset

    def set_sensors(self, sensors: Sequence[Sensor], preset: str = "") -> None:
        """Replace the whole sensor set (:meth:`SensorSet.set_all`; a scene's, or an undo)."""
        self.sensors.set_all(sensors, preset)

    def set_constraints(self, constraints: Sequence[Constraint]) -> None:
        """Replace the whole constraint list (:meth:`ConstraintList.set_all`)."""
        self.constraints.set_all(constraints)

    def drag_target(self, joint: str, world_pos: np.ndarray) -> None:
        """Move a tracker's target to ``world_pos`` (metres) by setting its drag offset."""
        base = self.tracked_position(joint, self.frame)
        self.sensors.edit(joint, offset=np.asarray(world_pos, float) - base)

    def simulate_failure(self, joint: str, frames: int, start: int | None = None) -> None:
        """Make ``joint``'s tracker lost for ``frames`` frames from ``start`` (default: now)."""
        start = self.frame if start is None else int(start)
        failures = self.sensors.require(joint).failures + ((start, start + int(frames)),)
        self.sensors.edit(joint, failures=failures)

    def tracked_position(self, joint: str, frame: int) -> np.ndarray:
        """Position (3,), metres, of ``joint``'s tracker at ``frame`` before any drag offset
        (:func:`engine.studio.clips.tracked_position`: newest snapshot, source or clip)."""
        return tracked_position(joint, frame, self.latest, self.source, self.motion, self.sensors.get(joint))

    # -- clip ------------------------------------------------------------------------
    @property
    def num_frames(self) -> int:
        """Frames of the sensor source or the clip (0 without either)."""
        return (
            int(self.source.num_frames) if self.source is not None else 0 if self.motion is None else len(self.motion)
        )

    def open(self, path: str | Path, rig_map: str | Path | None = None) -> None:
        """Load a BVH (with the joint mapping file ``rig_map`` if given); on failure raise
        :class:`UserError` and leave the session as it was."""
        motion = load_clip(path, rig_map)
        self.rig_map = Path(rig_map) if rig_map else None
        self.set_motion(motion, Path(path))

    def set_motion(self, motion: Motion, path: Path | None = None) -> None:
        self._close_source()
        if path is None:
            self.rig_map = None
        self.motion, self.path, self.frame = motion, path, 0
        self.pause_pending = False
        self.opened += 1
        self.clip_opened = self.opened
        self._send(cmd.SetMotion(motion, self.opened))
        self.events.motion.emit(ev.MotionChanged(motion, path))
        self._from_start()

    def set_source(self, source: SensorSource, name: str = "") -> None:
        """Read sensors from ``source`` instead of a clip: a tracker recording
        (:class:`engine.tracker_io.recording_source.RecordingSource`) or a live stream
        (:class:`engine.tracker_io.live_source.LiveSource`), which the session now owns and
        closes when another clip or source replaces it."""
        self._close_source()
        self.motion, self.path, self.frame = None, None, 0
        self.pause_pending = False
        self.source = source
        self.opened += 1
        self.clip_opened = self.opened
        command = cmd.SetSource(source, self.opened)
        if isinstance(self.engine, EngineProcess) and not self.engine.can_send(command):
            self._engine_in_thread()  # sends the source with the rest of the session
        else:
            self._send(command)
        self.events.source.emit(ev.SourceChanged(source, name, source.live))
        self._from_start()

    def _from_start(self) -> None:
        """A new clip or source plays from frame 0, with the first preset if no sensors."""
        self._send(cmd.Seek(0))
        self.events.frame.emit(0)
        if not self.sensors:
            self.sensors.set_preset(next(iter(sensor_presets())))

    def connect_live(self, host: str, port: int, mapping: str = "", convention: str = "unity") -> LiveSource:
        """Listen for VMC trackers on ``host:port`` (``mapping``: tracker names to joints,
        ``convention``: the axes of the incoming poses) and read sensors from the stream.

        Raises
        ------
        UserError
            A bad mapping, or an address that cannot be listened on.
        """
        from engine.tracker_io.live_source import LiveSource
        from engine.tracker_io.trackers import TrackerMapping

        src = LiveSource(host, port, TrackerMapping.parse(mapping), convention).start()
        self.set_source(src, f"live {src.receiver.host}:{src.receiver.port}")
        return src

    def open_recording(self, path: str | Path) -> RecordingSource:
        """Read sensors from a tracker recording (JSON Lines); raises :class:`UserError`
        naming the file and line of a bad one."""
        from engine.tracker_io.recording_source import RecordingSource

        src = RecordingSource(path)
        self.set_source(src, Path(path).name)
        return src

    @property
    def live_source(self) -> LiveSource | None:
        """The live tracker stream sensors come from, if they do."""
        from engine.tracker_io.live_source import LiveSource

        return self.source if isinstance(self.source, LiveSource) else None

    # -- optimizer, method ---------------------------------------------------------
    def set_setting(self, name: str, value: Any) -> None:
        self.set_settings({name: value})

    def set_settings(self, values: Mapping[str, Any]) -> None:
        edit = SettingsEdit(values)  # a bad name or value fails here, naming it, not in the engine
        old = {k: self.settings.get(k) for k in edit}
        self.settings = self.settings | edit
        self._send(cmd.SetSettings(edit))
        self.events.settings.emit(ev.SettingsChanged(dict(edit), old))

    def replace_settings(self, values: Mapping[str, Any]) -> None:
        """Make ``values`` the settings set explicitly, the others back to the method's
        profile (an undo of a settings edit)."""
        edit = SettingsEdit(values)
        names = set(edit) | set(self.settings)
        old = {k: self.settings.get(k) for k in names}
        self.settings = edit
        self._send(cmd.SetSettings(edit, replace=True))
        self.events.settings.emit(ev.SettingsChanged({k: edit.get(k) for k in names}, old))

    def set_method(self, name: str, ghosts: tuple[str, ...] | None = None) -> None:
        """Show method ``name`` (and ``ghosts`` beside it if given). The same method with
        other ghosts is :meth:`set_ghosts`: the shown method keeps its state."""
        if name == self.method and ghosts is not None:
            self.set_ghosts(ghosts)
            return
        old, old_ghosts = self.method, self.ghosts
        self.method = name
        if ghosts is not None:
            self.ghosts = tuple(g for g in ghosts if g != name)
        self.opened += 1
        self._send(cmd.SetMethod(name, self.ghosts, self.opened))
        self.events.method.emit(ev.MethodChanged(name, self.ghosts, old, old_ghosts))

    @staticmethod
    def available_methods() -> list[str]:
        """Names of the registered reconstruction methods."""
        return list(available_methods())

    def set_ghosts(self, ghosts: tuple[str, ...]) -> None:
        """Draw ``ghosts`` beside the shown method; the shown method, its state and the
        solved frames' history stay (not a switch: no new ``opened``)."""
        old = self.ghosts
        self.ghosts = tuple(g for g in ghosts if g != self.method)
        if self.ghosts == old:
            return
        self._send(cmd.SetGhosts(self.ghosts))
        self.events.method.emit(ev.MethodChanged(self.method, self.ghosts, self.method, old))

    def note_method(self, name: str) -> None:
        """Mirror the engine's method when it refused a change (no command is sent)."""
        if name != self.method:
            old = self.method
            self.method = name
            self.events.method.emit(ev.MethodChanged(name, self.ghosts, old, self.ghosts, refused=True))

    # -- playback --------------------------------------------------------------------
    def seek(self, frame: int) -> None:
        frame = int(np.clip(frame, 0, max(self.num_frames - 1, 0)))
        self.frame = frame
        self.pause_pending = False  # the frame asked for stands
        self._send(cmd.Seek(frame))
        self.events.frame.emit(frame)

    def note_frame(self, frame: int) -> None:
        """Mirror the engine's frame while playing (no command is sent back)."""
        if frame != self.frame:
            self.frame = frame
            self.events.frame.emit(frame)

    def note_paused(self, frame: int) -> None:
        """Take the frame the engine stopped on after :meth:`pause` (no command is sent
        back); once per pause, and not after a seek made since."""
        if not self.pause_pending:
            return
        self.pause_pending = False
        if frame != self.frame:
            self.frame = frame
            self.events.frame.emit(frame)

    def step(self, delta: int = 1) -> None:
        """Pause and go ``delta`` frames from the frame on screen: while playing that is
        the engine's newest frame of this play run, which runs ahead of :attr:`frame`
        (the timeline takes it 10 times a second)."""
        base, snap = self.frame, self.latest
        if self.playing and snap is not None and snap.playing and snap.plays == self.plays:
            base = int(snap.frame)
        self.set_playing(False)
        self.seek(base + delta)

    def play(self) -> None:
        self.set_playing(True)

    def pause(self) -> None:
        self.set_playing(False)

    def set_playing(self, playing: bool) -> None:
        if bool(playing) == self.playing and not playing:
            return
        self.pause_pending = not playing
        self.playing = bool(playing)
        if self.playing:
            self._send_play()
        else:
            self._send(cmd.Pause())
        self._playback_changed()

    def note_stopped(self) -> None:
        """Mirror the engine stopping at the clip's end (no command is sent back)."""
        if self.playing:
            self.playing = False
            self._playback_changed()

    def set_playback(self, speed: float | None = None, loop: bool | None = None, pace: str | None = None) -> None:
        """Speed (x real time, > 0), loop, and pace (``every_frame`` or ``real_time``)."""
        if pace is not None and pace not in ev.PLAYBACK_PACES:
            raise UserError(f"playback pace must be one of {', '.join(ev.PLAYBACK_PACES)}, got {pace!r}")
        if speed is not None and not float(speed) > 0:
            raise UserError(f"playback speed must be > 0, got {speed}")
        self.speed = self.speed if speed is None else float(speed)
        self.loop = self.loop if loop is None else bool(loop)
        self.pace = self.pace if pace is None else pace
        if self.playing:
            self._send_play()
        self._playback_changed()

    def _playback_changed(self) -> None:
        self.events.playback.emit(ev.PlaybackChanged(self.playing, self.speed, self.loop, self.pace))

    # -- scenes ----------------------------------------------------------------------
    def to_scene(self) -> dict[str, Any]:
        """Plain-JSON description of the sensors, constraints and settings."""
        return scene_to_dict(
            self.path,
            self.method,
            self.preset,
            tuple(self.sensors.values()),
            self.constraints,
            self.settings,
            self.frame,
        )

    def apply_scene(self, scene: dict[str, Any], where: str = "scene") -> str:
        """Restore :meth:`to_scene` output (:func:`engine.studio.scenes.apply_scene`)."""
        return apply_scene(self, scene, where)
