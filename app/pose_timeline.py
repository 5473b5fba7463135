"""The pose window's timeline: the bake (cached until the next edit), playing it (once or
looped, from the current frame) and scrubbing to an in-between.

Going to a frame between keys makes the baked in-between the current pose (its latent,
where it stands, its facing and the targets interpolated there), so a key added on it
keeps the motion as it was; on a key the character takes the key's pose (the window).
While the bake plays, a scrub moves the playhead and playing goes on from there.
"""

from __future__ import annotations

import copy
from typing import Any

from PyQt6.QtCore import QObject, Qt, QTimer
from PyQt6.QtWidgets import QApplication

from engine.authoring.bake import Baked, bake, interpolated_heading, interpolated_targets
from engine.authoring.character import Pose
from engine.errors import UserError
from engine.kinematics.fk import fk_positions


class KeyPlayback(QObject):
    """Bake, play and scrub the keys of the pose window ``w`` (its ``scene``, ``vae``,
    ``mode``, ``keys`` strip)."""

    def __init__(self, w: Any) -> None:
        super().__init__(w)
        self.w = w
        self.baked: Baked | None = None
        self.frame = 0  # the frame playing
        self.timer = QTimer(self)
        self.timer.timeout.connect(self._tick)

    @property
    def playing(self) -> bool:
        return self.timer.isActive()

    def invalidate(self) -> None:
        """An edit: the next use bakes again."""
        self.baked = None

    def baked_scene(self) -> Baked:
        """The keys baked (cached until the next edit); a wait cursor while it bakes."""
        if self.baked is None:
            if not self.w.scene.keys:
                raise UserError("add at least one key first")
            QApplication.setOverrideCursor(Qt.CursorShape.WaitCursor)
            try:
                self.baked = bake(self.w.scene, self.w.vae)
            finally:
                QApplication.restoreOverrideCursor()
        return self.baked

    # -- playing -------------------------------------------------------------------
    def toggle(self) -> None:
        """Play from the current frame (from the start when it is the last), or stop."""
        if self.playing:
            self.stop()
            return
        self.baked_scene()
        last = len(self.baked.motion) - 1
        self.frame = 0 if self.w.frame >= last else self.w.frame
        self.timer.start(int(1000 / self.w.scene.animation.fps))
        self.w.keys.set_playing(True)

    def stop(self) -> None:
        """Stop playing; the frame reached becomes the current one."""
        if not self.playing:
            return
        self.timer.stop()
        self.w.keys.set_playing(False)
        self.w.go_to(self.frame)

    def seek(self, frame: int) -> None:
        """While playing: go on from ``frame``."""
        self.frame = int(frame)
        self._show(self.frame)

    def _tick(self) -> None:
        n = len(self.baked.motion) if self.baked is not None else 0
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
        motion = self.baked.motion
        f = min(frame, len(motion) - 1)
        self.w.show_positions(fk_positions(motion.local_rot[f], motion.root_pos[f], motion.skeleton.offsets))
        a = self.w.scene.animation
        self.w.keys.set_state(a.frames, a.fps, tuple(k.frame for k in self.w.scene.keys), f)

    # -- scrubbing -----------------------------------------------------------------
    def pose_between(self, frame: int) -> None:
        """Make the baked in-between at ``frame`` the window's current pose (see the module doc)."""
        baked = self.baked_scene()
        motion, m = baked.motion, self.w.mode
        f = min(int(frame), len(motion) - 1)
        local, root = motion.local_rot[f].copy(), motion.root_pos[f].copy()
        m.pose = Pose(baked.latents[f].copy(), local, root, fk_positions(local, root, motion.skeleton.offsets))
        keys = self.w.scene.keys
        times = [float(k.frame) for k in keys]
        scheme = self.w.scene.animation.interpolation
        m.heading = interpolated_heading(keys, times, f, scheme)
        m.targets = {t.joint: copy.deepcopy(t) for t in interpolated_targets(keys, times, f, scheme)}
