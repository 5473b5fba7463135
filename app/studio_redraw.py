"""The studio window's view of its session's events (:mod:`engine.studio.events`): each
event updates only the widget that shows what changed (the timeline, the sensor,
constraint and optimizer panels, the plots, the motion paths, the camera on a new clip,
the busy notice while a method or a clip starts). :meth:`StudioRedraw.refresh` shows the
panels' whole state; :meth:`StudioRedraw.close` stops listening.
"""

from __future__ import annotations

from typing import Any

from app.shell import StudioShell
from engine.authoring.motion_paths import clip_paths
from engine.studio import events as ev


class StudioRedraw:
    """The updates of the studio window ``w`` from its session's events (see the module doc)."""

    def __init__(self, w: StudioShell) -> None:
        self.w = w
        # each event updates only the widget showing what changed (a sensor drag touches
        # the sensor panel alone; the 3D view follows the engine's snapshots)
        e = self.w.session.events
        e.frame.connect(self.w.timeline.set_frame)
        e.playback.connect(self._show_playback)
        e.motion.connect(self._show_motion)
        e.source.connect(self._show_source)
        e.sensors.connect(self._show_sensors)
        e.sensors.connect(self.w.ghost_status.sensors_changed)
        e.constraints.connect(self._show_constraints)
        e.settings.connect(self._show_optimizer)
        e.method.connect(self._show_optimizer)
        e.method.connect(self._announce_method)
        e.motion.connect(self._announce_motion)

    def refresh(self) -> None:
        """Show the session's sensors, constraints and optimizer settings."""
        self._show_sensors(None)
        self._show_constraints(None)
        self._show_optimizer(None)

    def close(self) -> None:
        """Stop listening to the session (the window closes)."""
        e = self.w.session.events
        for signal, slot in (
            (e.frame, self.w.timeline.set_frame),
            (e.playback, self._show_playback),
            (e.motion, self._show_motion),
            (e.source, self._show_source),
            (e.sensors, self._show_sensors),
            (e.sensors, self.w.ghost_status.sensors_changed),
            (e.constraints, self._show_constraints),
            (e.settings, self._show_optimizer),
            (e.method, self._show_optimizer),
            (e.method, self._announce_method),
            (e.motion, self._announce_motion),
        ):
            signal.disconnect(slot)

    def _seq(self) -> int:
        snap = self.w.session.latest
        return -1 if snap is None else snap.seq

    def _announce_method(self, event: ev.MethodChanged) -> None:
        if event.method != event.old_method and not event.refused:  # a refusal switches nothing
            self.w.busy.begin(event.method, self._seq(), "Switching to")

    def _announce_motion(self, event: ev.MotionChanged) -> None:
        self.w.busy.begin(self.w.session.method, self._seq(), "Opening the clip with")

    def _show_playback(self, event: ev.PlaybackChanged) -> None:
        self.w.timeline.set_playing(event.playing)
        self.w.timeline.set_pace(event.pace)

    def _show_motion(self, event: ev.MotionChanged) -> None:
        if not self.w.undo.editing_clip:  # another clip: its frames are not the selected ones
            self.w.timeline.set_selection(None)
            self.w.opened_motion = event.motion  # what clip_saving compares against
        self.w.timeline.set_range(self.w.session.num_frames, event.motion.fps)
        self.w.constraint_panel.frames_changed()
        self.w.plots.clear()
        self.w.method_errors.clear()
        self.w.motion_paths.set_source(lambda m=event.motion: clip_paths(m))  # computed when drawn
        if self.w.undo.editing_clip:
            # the same clip edited (a range re-solve, its undo): the frame on screen and
            # the camera the user set stay; frame 0's placement would show the character
            # off-centre and near until something moved the camera again
            return
        self.w.viewport.reset_camera(event.motion.root_pos[0])
        # the clip at once, the solve behind it (the first solved frame takes seconds);
        # nothing of the clip or source before stays beside it
        self.w.viewport.clear_pose()
        self.w.viewport.show_clip_frame(event.motion.slice(0, 1).positions()[0])

    def _show_source(self, event: ev.SourceChanged) -> None:
        """Another sensor source: the previous clip's or stream's character goes at once
        (a live stream may send its first frame much later, or never)."""
        waiting = event.live and event.source.num_frames == 0
        self.w.viewport.clear_pose(f"waiting for tracker frames ({event.name})" if waiting else "")
        # the clip's errors against its ground truth and its joints' paths: a source of
        # trackers has neither
        self.w.plots.clear()
        self.w.method_errors.clear()
        self.w.motion_paths.set_source(None)

    def _show_sensors(self, event: ev.SensorsChanged | None) -> None:
        s = self.w.session
        if event is not None and event.old is not None and event.new is not None:
            # one tracker edited (a target drag sends one per mouse move): its row only
            if event.old.dof != event.new.dof:
                self.w.viewport.oriented = frozenset(j for j, c in s.sensors.items() if c.dof == 6)
            self.w.sensor_panel.set_sensor(event.joint, event.new)
            return
        self.w.viewport.oriented = frozenset(j for j, c in s.sensors.items() if c.dof == 6)
        self.w.sensor_panel.set_sensors(s.preset, s.sensors)

    def _show_constraints(self, event: ev.ConstraintsChanged | None) -> None:
        self.w.constraint_panel.set_constraints([c.to_dict() for c in self.w.session.constraints])

    def _show_optimizer(self, event: Any = None) -> None:
        s = self.w.session
        # settings the session has not set yet show the engine's defaults
        self.w.optimizer_panel.set_state(s.method, s.ghosts, {**self.w.optimizer_defaults, **s.settings})
        self.w.ghost_status.apply()  # a ghost that cannot run stays disabled
