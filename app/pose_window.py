"""The pose and key window (File ▸ New pose): pose the character by its joints, key it.

The window holds an :class:`engine.authoring.pose_mode.PoseMode` and the animation being
authored (an :class:`engine.authoring.document.AuthoringScene`). A drag on a joint
creates a target there and moves it and selects the joint (its rotation rings show: a
ring dragged turns it about that world axis); a drag on a target's sphere moves it; a
drag on the hips moves the whole body and their ring turns it (root motion). Every move
solves the pose again (the continuous solve, on the GUI thread: a few milliseconds with
targets only). The target list enables, weights and clears targets; the key timeline
(:mod:`app.pose_timeline`) adds the current pose as a key at the current frame (its
latent, targets, place and facing), drags and deletes keys, scrubs through the baked
in-betweens and plays them. The Constraints dock adds any constraint kind to the pose
(:mod:`app.pose_constraints`). Every edit is one undo step (Ctrl+Z / Ctrl+Shift+Z);
closing with unsaved edits asks first. Files: :mod:`app.pose_files`.
"""

from __future__ import annotations

import copy
from typing import Any

import numpy as np
from PyQt6.QtCore import Qt
from PyQt6.QtGui import QCloseEvent, QUndoStack
from PyQt6.QtWidgets import (
    QApplication, QDockWidget, QDoubleSpinBox, QFrame, QLabel, QMainWindow, QMessageBox, QScrollArea, QWidget,
)  # fmt: skip

from app.camera_keys import CameraKeys
from app.pose_constraints import PoseConstraints
from app.pose_files import PoseFiles
from app.pose_menus import build_pose_menus
from app.pose_timeline import KeyPlayback
from app.pose_turns import JointTurns
from app.undo import StateCommand
from engine import skeleton as sk
from engine.authoring.document import AuthoringScene
from engine.authoring.keys import Animation, Key
from engine.authoring.pose_mode import PoseMode
from engine.errors import UserError
from widgets.key_strip import KeyStrip
from widgets.target_list import TargetList
from widgets.viewport.viewport import Viewport


#: Width of the side panels (targets, constraints), pixels: wide enough for a target row.
SIDE_PANEL_PX = 330


class PoseWindow(QMainWindow):
    """See the module doc. ``vae``: the pose VAE; ``mode``: the starting pose mode."""

    def __init__(self, vae: Any, mode: PoseMode, parent: QWidget | None = None) -> None:
        super().__init__(parent)
        self.setWindowTitle("DragPoser studio: pose and keys")
        self.vae, self.mode = vae, mode
        self.scene = AuthoringScene(animation=Animation(), height=mode.character.height)
        self.frame, self.dirty = 0, False
        self.undo = QUndoStack(self)
        self.undo.cleanChanged.connect(lambda clean: setattr(self, "dirty", not clean))
        self.viewport = Viewport(self)
        self.viewport.ground_truth.update(None)
        self.setCentralWidget(self.viewport)
        self.selected: str | None = None  # the joint whose rotation rings are shown
        self.turns = JointTurns(self)
        self.viewport.ringTurned.connect(self.turns.by_ring)
        self.viewport.jointDragged.connect(self.drag_joint)
        self.viewport.targetDragged.connect(self.drag_joint)
        # in pose mode a plain press grabs a joint too (the studio's view needs Ctrl, where
        # a plain press on the body turns the camera); off every joint the camera turns
        dragger = self.viewport.joints
        on_target = dragger.press_target
        dragger.press_target = lambda x, y: on_target(x, y) or dragger.press(x, y)
        self.targets = TargetList()
        self.targets.enabledChanged.connect(lambda j, on: self.edit_target(j, enabled=on))
        self.targets.weightChanged.connect(lambda j, w: self.edit_target(j, weight=w))
        self.targets.turnHeld.connect(self.turns.hold)
        self.targets.clearRequested.connect(self.clear_target)
        self.targets.clearAllRequested.connect(self.clear_all)
        self._dock("Targets", self.targets, Qt.DockWidgetArea.RightDockWidgetArea)
        self.constraints = PoseConstraints(self)
        self.keys = KeyStrip()
        self.keys.frameChanged.connect(self.go_to)
        self.keys.addRequested.connect(self.add_key)
        self.keys.deleteRequested.connect(self.delete_key)
        self.keys.moveRequested.connect(self.move_key)
        self.keys.lengthChanged.connect(lambda n: self.edit("length", lambda: setattr(self.scene.animation, "frames", n)))
        self.keys.fpsChanged.connect(lambda f: self.edit("rate", lambda: setattr(self.scene.animation, "fps", f)))
        self.keys.interpolationChanged.connect(
            lambda v: self.edit("in-betweens", lambda: setattr(self.scene.animation, "interpolation", v)))
        self.keys.previewRequested.connect(lambda: self._guard("Play", self.playback.toggle))
        self._dock("Keys", self.keys, Qt.DockWidgetArea.BottomDockWidgetArea)
        body = self.addToolBar("Body")
        body.setMovable(False)
        body.addWidget(QLabel(" Body: drag the hips to move it; facing "))
        self.facing = QDoubleSpinBox(minimum=-180.0, maximum=180.0, decimals=1, singleStep=15.0, suffix=" deg",
                                     wrapping=True)  # fmt: skip
        self.facing.setToolTip("Where the whole body faces, degrees about the vertical (0: towards -Y, the front view)")
        self.facing.valueChanged.connect(self.turn_body)
        body.addWidget(self.facing)
        self.playback = KeyPlayback(self)
        self.files = PoseFiles(self)
        build_pose_menus(self)
        self.camera_keys = CameraKeys(self.viewport, self)
        QApplication.instance().installEventFilter(self.camera_keys)
        self.refresh()

    # -- layout --------------------------------------------------------------------
    def _dock(self, title: str, widget: QWidget, area: Qt.DockWidgetArea) -> None:
        dock = QDockWidget(title, self)
        if area == Qt.DockWidgetArea.RightDockWidgetArea:
            # a side panel scrolls instead of widening: rows and long joint names that
            # appear while posing would otherwise push the 3D view aside between drags
            scroll = QScrollArea()
            scroll.setWidgetResizable(True)
            scroll.setHorizontalScrollBarPolicy(Qt.ScrollBarPolicy.ScrollBarAlwaysOff)
            scroll.setFrameShape(QFrame.Shape.NoFrame)
            scroll.setMinimumWidth(SIDE_PANEL_PX)
            scroll.setWidget(widget)
            widget = scroll
        dock.setWidget(widget)
        dock.setFeatures(QDockWidget.DockWidgetFeature.NoDockWidgetFeatures)
        self.addDockWidget(area, dock)

    # -- undoable state ------------------------------------------------------------
    def _state(self) -> tuple:
        a = self.scene.animation
        return (copy.deepcopy(self.mode.targets), copy.deepcopy(self.scene.keys), (a.frames, a.fps, a.interpolation),
                self.mode.pose, self.constraints.state(), self.mode.heading, copy.deepcopy(self.mode.planted))  # fmt: skip

    def _restore(self, state: tuple) -> None:
        targets, keys, (frames, fps, interpolation), pose, constraints, self.mode.heading, planted = state
        self.mode.planted = copy.deepcopy(planted)
        self.constraints.restore(constraints)
        self.mode.targets, self.scene.keys = copy.deepcopy(targets), copy.deepcopy(keys)
        a = self.scene.animation
        a.frames, a.fps, a.interpolation = frames, fps, interpolation
        self.mode.pose = pose
        self.playback.invalidate()
        self.refresh()

    def edit(self, text: str, change, key: tuple | None = None, solve: bool = False) -> None:
        """Apply ``change()`` as one undo step (merging drags of the same ``key``)."""
        self.playback.stop()
        before = self._state()
        try:
            change()
            if solve:
                self.mode.solve()
        except UserError as exc:
            self._restore(before)
            QMessageBox.warning(self, "Pose", str(exc))
            return
        self.playback.invalidate()
        self.undo.push(StateCommand(text, self._restore, before, self._state(), key))
        self.refresh()

    def _guard(self, title: str, action) -> None:
        """Run ``action()``; a UserError becomes a message box titled ``title``."""
        try:
            action()
        except UserError as exc:
            QMessageBox.information(self, title, str(exc))

    # -- targets -------------------------------------------------------------------
    def drag_joint(self, joint: str, position: np.ndarray) -> None:
        """Create or move the target on ``joint`` to ``position (3,)`` metres and solve;
        with Alt held, turn it instead (:meth:`app.pose_turns.JointTurns.alt_drag`)."""
        self.selected = joint
        if QApplication.keyboardModifiers() & Qt.KeyboardModifier.AltModifier:
            self.turns.alt_drag(joint, position)
            return
        self.turns.gesture = None
        if joint == "root":
            self.move_body(np.asarray(position, float) - self.mode.pose.root_pos)
            return
        key = ("target", joint, "position")
        self.edit(f"move target {joint}", lambda: self.mode.set_target(joint, np.asarray(position, float)), key,
                   solve=True)  # fmt: skip

    def deselect(self) -> None:
        """Hide the rotation rings."""
        self.selected = None
        self.refresh()

    def move_body(self, delta: np.ndarray) -> None:
        """Root motion: translate the whole body horizontally by ``delta (3,)`` metres
        (its height is the floor's business), then solve the targets from there."""
        d = np.array([delta[0], delta[1], 0.0])

        def change() -> None:
            self.mode.pose = self.mode.pose.moved(d)
            self.mode.plant_where_standing()
            if self.mode.targets:
                self.mode.solve()

        self.edit("move body", change, ("body", "root", "position"))

    def turn_body(self, heading: float) -> None:
        """Root motion: face ``heading`` degrees about +Z (0 faces -Y), the whole body
        turned about its root, then the targets solved from there."""
        turn = float(heading) - self.mode.heading
        if abs(turn) < 1e-9:
            return

        def change() -> None:
            self.mode.heading = float(heading)
            self.mode.pose = self.mode.pose.turned(turn)
            self.mode.plant_where_standing()
            if self.mode.targets:
                self.mode.solve()

        self.edit("turn body", change, ("body", "root", "heading"))

    def edit_target(self, joint: str, **fields: Any) -> None:
        """Change a target's ``enabled`` or ``weight`` and solve."""
        self.edit(f"edit target {joint}", lambda: self.mode.set_target(joint, **fields), solve=True)

    def clear_target(self, joint: str) -> None:
        self.edit(f"clear target {joint}", lambda: self.mode.remove_target(joint), solve=True)

    def clear_all(self) -> None:
        """Remove every target and put the character back in its starting pose, on the
        feet where it stands now (one undo step)."""

        def change() -> None:
            m = self.mode
            m.clear_targets()
            feet = np.mean([p[:2] for p in m.planted.values()], axis=0)
            pose = m.character.decode(m.base_latent, m.character.grounded(m.pose.root_pos[:2], m.heading))
            shift = feet - np.mean([pose.positions[sk.JOINT_INDEX[j], :2] for j in m.planted], axis=0)
            m.pose = m.character.decode(m.base_latent, m.character.grounded(pose.root_pos[:2] + shift, m.heading))
            m.plant_where_standing()

        self.edit("clear all targets", change)

    def settle(self) -> None:
        """An offline solve of the current targets (one undo step); a wait cursor while it
        runs (seconds with constraints on a loaded machine)."""
        QApplication.setOverrideCursor(Qt.CursorShape.WaitCursor)
        try:
            self.edit("settle pose", self.mode.settle)
        finally:
            QApplication.restoreOverrideCursor()

    # -- keys ----------------------------------------------------------------------
    def _key_at(self, frame: int) -> Key | None:
        return next((k for k in self.scene.keys if k.frame == frame), None)

    def add_key(self, frame: int) -> None:
        """The current pose (latent, targets, where it stands) as the key at ``frame``."""
        p = self.mode.pose

        def change() -> None:
            self.scene.keys = [k for k in self.scene.keys if k.frame != frame]
            key = Key(int(frame), copy.deepcopy(self.mode.targets), p.latent.copy(), p.root_pos[:2].copy(),
                      self.mode.heading)  # fmt: skip
            self.scene.keys = sorted([*self.scene.keys, key], key=lambda k: k.frame)

        self.edit(f"key frame {frame}", change)

    def delete_key(self, frame: int) -> None:
        if self._key_at(frame) is not None:
            self.edit(f"delete key {frame}", lambda: setattr(self.scene, "keys", [k for k in self.scene.keys if k.frame != frame]))

    def move_key(self, frame: int, to: int) -> None:
        key = self._key_at(frame)
        if key is None or frame == to or not 0 <= to < self.scene.animation.frames:
            return

        def change() -> None:
            self.scene.keys = [k for k in self.scene.keys if k.frame not in (frame, to)]
            moved = copy.deepcopy(key)
            moved.frame = int(to)
            self.scene.keys = sorted([*self.scene.keys, moved], key=lambda k: k.frame)
            self.go_to(to)  # inside the step: the pose it shows is what undo and redo give back

        self.edit(f"move key {frame} -> {to}", change)

    def step(self, by: int) -> None:
        """Go ``by`` frames on (or back), within the animation."""
        self.go_to(max(0, min(self.scene.animation.frames - 1, self.frame + by)))

    def step_key(self, by: int) -> None:
        """Go to the next (``by`` > 0) or previous key, if there is one."""
        frames = [k.frame for k in self.scene.keys if (k.frame - self.frame) * by > 0]
        if frames:
            self.go_to(min(frames) if by > 0 else max(frames))

    def go_to(self, frame: int) -> None:
        """Make ``frame`` current: on a key, pose the character as that key; between
        keys, as the baked in-between (:mod:`app.pose_timeline`); while the bake plays,
        go on playing from there."""
        if self.playback.playing:
            self.playback.seek(frame)
            return
        self.frame = int(frame)
        key = self._key_at(self.frame)
        if key is None and self.scene.keys:
            try:
                self.playback.pose_between(self.frame)
            except UserError as exc:
                QMessageBox.warning(self, "Keys", str(exc))
        if key is not None:
            self.mode.targets = copy.deepcopy(key.targets)
            if key.latent is not None:
                self.mode.heading = key.heading
                ctx = self.mode.character.grounded(key.root, key.heading)
                self.mode.pose = self.mode.character.decode(key.latent, ctx)
                self.mode.plant_where_standing()
                self.mode.solve(0)  # the exact limb steps onto the key's targets
        self.refresh()

    # -- drawing and closing -------------------------------------------------------
    def hips(self) -> np.ndarray:
        """The shown pose's hips (3,) metres: what the camera presets look at."""
        return self.mode.pose.positions[0]

    def set_display(self, mode: str) -> None:
        """Draw the character as a ``stick`` figure or a shaded ``body``."""
        self.viewport.set_display(mode)
        self.show_positions(self.mode.pose.positions)

    def show_positions(self, positions: np.ndarray) -> None:
        """Draw the character at ``positions (22, 3)`` metres (a pose or a played frame)."""
        vp = self.viewport
        (vp.body if vp.display == "body" else vp.reconstruction).update(positions)
        self.viewport.joints.positions = positions
        self.viewport.plotter.render()

    def refresh(self) -> None:
        """Show the pose, its targets, the target list and the key strip."""
        t = self.mode.targets
        self.viewport.sensors.update(tuple(t), np.array([x.position for x in t.values()]).reshape(-1, 3),
                                     np.array([x.rotation if x.rotation is not None else [1.0, 0, 0, 0]
                                               for x in t.values()]).reshape(-1, 4),
                                     np.array([x.active for x in t.values()], bool),
                                     tuple(x.rotation is not None for x in t.values()))  # fmt: skip
        self.targets.set_targets({j: (x.enabled, x.weight, x.rotation is not None) for j, x in t.items()})
        a = self.scene.animation
        self.keys.set_state(a.frames, a.fps, tuple(k.frame for k in self.scene.keys), self.frame, a.interpolation)
        self.constraints.refresh()
        self.facing.blockSignals(True)
        self.facing.setValue((self.mode.heading + 180.0) % 360.0 - 180.0)
        self.facing.blockSignals(False)
        self.turns.show_handles()
        self.show_positions(self.mode.pose.positions)

    def closeEvent(self, event: QCloseEvent | None) -> None:  # noqa: N802 (Qt's name)
        if event is None:
            return
        if not self.files.confirm_discard("closing"):
            event.ignore()
            return
        self.playback.timer.stop()
        QApplication.instance().removeEventFilter(self.camera_keys)
        if not getattr(self.viewport.plotter, "_closed", False):  # a second close would free VTK twice
            self.viewport.close()
        event.accept()
