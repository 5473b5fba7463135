"""The pose window's timeline: the bake of the keys (on a worker, with progress and
Cancel), playing it (once or looped, from the current frame) and seeking while it plays.

The model (:class:`engine.authoring.session.AuthoringSession`) keeps the bake until an
edit makes it stale; :meth:`KeyPlayback.baked_scene` bakes again off the GUI thread
(:class:`app.job_runner.JobRunner`: the window keeps drawing, a window-modal progress
dialog offers Cancel) and hands the result to the model on the GUI thread. Scrubbing to
an in-between is the model's :meth:`~engine.authoring.session.AuthoringSession.go_to`.
While the bake plays, a scrub moves the playhead and playing goes on from there.
"""

from __future__ import annotations

from typing import Any

from PyQt6.QtCore import QObject, QTimer

from engine.authoring.bake import Baked
from engine.errors import UserError
from engine.kinematics.fk import fk_positions


class KeyPlayback(QObject):
    """Bake, play and seek the keys of the pose window ``w`` (its ``session``, ``jobs``,
    ``keys`` strip)."""

    def __init__(self, w: Any) -> None:
        super().__init__(w)
        self.w = w
        self.frame = 0  # the frame playing
        self.timer = QTimer(self)
        self.timer.timeout.connect(self._tick)

    @property
    def playing(self) -> bool:
        return self.timer.isActive()

    @property
    def baked(self) -> Baked | None:
        """The model's bake (None while it is stale)."""
        return self.w.session.baked

    def baked_scene(self) -> Baked:
        """The keys baked: the model's bake, or a new one from the worker (the event loop
        runs meanwhile); a UserError when there are no keys or the bake was cancelled."""
        session = self.w.session
        if session.baked is None:
            job = session.bake_job()
            runner = self.w.jobs
            runner.start(job, lambda baked: session.take_bake(job, baked), modal=True)
            runner.wait()
            if session.baked is None:
                raise UserError(f"the bake did not finish: {runner.message}")
        return session.baked

    # -- playing -------------------------------------------------------------------
    def toggle(self) -> None:
        """Play from the current frame (from the start when it is the last), or stop."""
        if self.playing:
            self.stop()
            return
        baked = self.baked_scene()
        last = len(baked.motion) - 1
        self.frame = 0 if self.w.frame >= last else self.w.frame
        self.timer.start(int(1000 / self.w.scene.animation.fps))
        self.w.keys.set_playing(True)
        # the targets and rings belong to the pose being edited, not to the played frames
        vp = self.w.viewport
        vp.sensors.set_shown(False)
        vp.rings.hide()
        vp.rings.show_facing(None)

    def stop(self) -> None:
        """Stop playing; the frame reached becomes the current one."""
        if not self.playing:
            return
        self.timer.stop()
        self.w.keys.set_playing(False)
        self.w.viewport.sensors.set_shown(True)
        self.w.go_to(self.frame)
        self.w.turns.show_handles()
        self.w.viewport.plotter.render()

    def seek(self, frame: int) -> None:
        """While playing: go on from ``frame``."""
        self.frame = int(frame)
        self._show(self.frame)

    def _tick(self) -> None:
        baked = self.baked
        n = len(baked.motion) if baked is not None else 0
        if n == 0:
            self.stop()
            return
        nxt = self.frame + 1
        if nxt >= n:
            if not self.w.keys.loop.isChecked():
                self.stop()
                return
            nxt = 0
        self.frame = nxt
        self._show(nxt)

    def _show(self, frame: int) -> None:
        baked = self.baked
        if baked is None:
            return
        motion = baked.motion
        f = min(frame, len(motion) - 1)
        positions = fk_positions(motion.local_rot[f], motion.root_pos[f], motion.skeleton.offsets)
        self.w.redraw.show_gizmos(positions, f)
        self.w.show_positions(positions)
        a = self.w.scene.animation
        self.w.keys.set_state(a.frames, a.fps, tuple(k.frame for k in self.w.scene.keys), f)
