"""The pose and key window (File ▸ New pose): pose the character by its joints, key it.

The window is a view of an :class:`engine.authoring.session.AuthoringSession`, the
Qt-free model that owns the pose, the targets, the keys, the constraints and the undo
history: every gesture calls one model method (one undo step) and the window redraws
what the model's events say changed (:mod:`app.pose_redraw`); the gestures on the body live
in :mod:`app.pose_gestures`. A click on a joint selects it (its rotation rings
show: a ring dragged turns it about that world axis; its motion path shows,
:mod:`app.motion_path_view`); a drag on a joint creates a target there and moves it and
selects the joint (a wrist or an ankle at the depth :mod:`engine.authoring.drag_reach`
gives); a drag on a target's sphere moves it; a drag on the hips moves the whole
body sideways and lowers or raises the pelvis up and down the screen, over the planted
feet (a squat), and their ring turns it (root motion); Shift + drag on the hips moves the
pelvis alone, the feet planted flat and the upper body carried. Every move solves the pose again (the
continuous solve, on the GUI thread: a few milliseconds with targets only). The target
list enables, weights and clears targets; the key timeline (:mod:`app.pose_timeline`)
adds the current pose as a key at the current frame, drags and deletes keys, scrubs
through the baked in-betweens and plays them; the bake runs on a worker thread behind a
progress dialog with Cancel (:mod:`app.job_runner`). The Constraints dock adds any
constraint kind to the pose (:mod:`app.pose_constraints`); their gizmos are drawn and
dragged as in the studio. Ctrl+Z / Ctrl+Shift+Z undo
and redo through the model; closing with unsaved edits asks first. Files:
:mod:`app.pose_files`.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np
from PyQt6.QtCore import QSettings, Qt, QTimer
from PyQt6.QtGui import QCloseEvent
from PyQt6.QtWidgets import (
    QApplication,
    QDockWidget,
    QDoubleSpinBox,
    QFrame,
    QLabel,
    QMainWindow,
    QMessageBox,
    QScrollArea,
    QWidget,
)

from app.camera_keys import CameraKeys
from app.job_runner import JobRunner
from app.motion_path_view import MotionPathView
from app.pose_constraints import PoseConstraints
from app.pose_files import PoseFiles
from app.pose_gestures import PoseGestures
from app.pose_menus import build_pose_menus
from app.pose_naturalness import NaturalnessReadout
from app.pose_redraw import PoseRedraw
from app.pose_timeline import KeyPlayback
from app.pose_turns import JointTurns
from app.status_bar import StatusBar
from engine.authoring.document import AuthoringScene
from engine.authoring.history import History
from engine.authoring.pose_mode import PoseMode
from engine.authoring.session import AuthoringSession
from engine.errors import UserError
from widgets.help_dialog import POSE_MOUSE
from widgets.key_strip import KeyStrip
from widgets.target_list import TargetList
from widgets.viewport.viewport import Viewport

#: Width of the side panels (targets, constraints), pixels: wide enough for a target row.
SIDE_PANEL_PX = 330


class PoseWindow(PoseGestures, QMainWindow):
    """See the module doc. ``session``: the authoring model the window shows and edits;
    ``settings``: where dialogs remember their choices (default: the studio's)."""

    mouse_help = POSE_MOUSE

    def __init__(
        self, session: AuthoringSession, parent: QWidget | None = None, settings: QSettings | None = None
    ) -> None:
        super().__init__(parent)
        self.setWindowTitle("DragPoser studio: pose and keys")
        self.session = session
        self.settings = settings or QSettings("dragposer-studio", "studio")
        self.undo: History = session.history
        self.jobs = JobRunner(self)
        self.autosave: Any = None  # an app.autosave.DocumentAutosave when the studio autosaves
        self.viewport = Viewport(self)
        self.viewport.ground_truth.update(None)
        self.setCentralWidget(self.viewport)
        self.turns = JointTurns(self)
        self.viewport.ringTurned.connect(self.turns.by_ring)
        self.viewport.jointSelected.connect(self.select)
        self.viewport.mouseReleased.connect(self.session.release)
        self.viewport.jointDragged.connect(self.drag_joint)
        self.viewport.targetDragged.connect(self.drag_joint)
        self.viewport.gizmoEdited.connect(lambda name, changes: self.constraints.update(name, changes))
        self._reach = None  # the limb of the joint pressed (PoseGestures)
        self.viewport.joints.place = self._placed
        # in pose mode a plain press grabs a joint too (the studio's view needs Ctrl, where
        # a plain press on the body turns the camera); off every joint the camera turns
        self.viewport.joints.plain_press_grabs_joints = True
        # the hips move on an upright plane: up and down the screen lowers or raises the
        # pelvis (a squat), sideways moves the body (AuthoringSession.drag_hips)
        self.viewport.joints.upright = frozenset({"root"})
        # ... from the body's place, which a balanced crouch leaves in front of the pelvis
        self.viewport.joints.drag_origin = lambda name: self.session.hips_handle() if name == "root" else None
        # Shift + drag near the hips moves the pelvis alone (AuthoringSession.drag_pelvis)
        self.viewport.joints.shift_grabs = "root"
        # the hip joints move only with the pelvis: a press on them grabs the hips
        self.viewport.joints.stand_ins = {"lhip": "root", "rhip": "root"}
        self.targets = TargetList()
        self.targets.enabledChanged.connect(lambda j, on: self.edit_target(j, enabled=on))
        self.targets.weightChanged.connect(lambda j, w: self.edit_target(j, weight=w))
        self.targets.turnHeld.connect(self.turns.hold)
        self.targets.clearRequested.connect(self.clear_target)
        self.targets.clearAllRequested.connect(self.clear_all)
        targets_dock = self._dock("Targets", self.targets, Qt.DockWidgetArea.RightDockWidgetArea)
        self.constraints = PoseConstraints(self)
        # the right column shared equally: left to their size hints, the constraints' list
        # takes two thirds of it and the Targets panel scrolls from its second target on
        self.resizeDocks([targets_dock, self.constraints.dock], [1, 1], Qt.Orientation.Vertical)
        self.keys = KeyStrip()
        self.keys.frameChanged.connect(self.go_to)
        self.keys.addRequested.connect(self.add_key)
        self.keys.deleteRequested.connect(self.delete_key)
        self.keys.moveRequested.connect(self.move_key)
        self.keys.lengthChanged.connect(lambda n: self._edit(lambda: session.set_length(n)))
        self.keys.fpsChanged.connect(lambda f: self._edit(lambda: session.set_fps(f)))
        self.keys.interpolationChanged.connect(lambda v: self._edit(lambda: session.set_interpolation(v)))
        self.keys.previewRequested.connect(lambda: self._guard("Play", self.playback.toggle))
        self._dock("Keys", self.keys, Qt.DockWidgetArea.BottomDockWidgetArea)
        body = self.addToolBar("Body")
        body.setMovable(False)
        body.addWidget(QLabel(" Body: drag the hips to move it (down: squat; Shift: pelvis only); facing "))
        self.facing = QDoubleSpinBox(
            minimum=-180.0, maximum=180.0, decimals=1, singleStep=15.0, suffix=" deg", wrapping=True
        )
        self.facing.setToolTip("Where the whole body faces, degrees about the vertical (0: towards -Y, the front view)")
        self.facing.valueChanged.connect(self.turn_body)
        body.addWidget(self.facing)
        self.playback = KeyPlayback(self)
        # the status bar from the start: QMainWindow would make it on the first message,
        # and its arrival would push the 3D view and the key timeline up under the mouse
        self.setStatusBar(StatusBar())
        self.statusBar().setSizeGripEnabled(False)
        self.naturalness = NaturalnessReadout()
        self.statusBar().addPermanentWidget(self.naturalness)
        self.files = PoseFiles(self)
        self.paths = MotionPathView(self.viewport.paths, self.settings, self._render_soon)
        build_pose_menus(self)
        self.camera_keys = CameraKeys(self.viewport, self)
        QApplication.instance().installEventFilter(self.camera_keys)
        self._render_pending = False
        self._asked_to_close = False  # the studio's quit asked already (close_unasked)
        self.redraw = PoseRedraw(self)
        self.redraw.refresh()
        self.redraw.paths_due()

    # -- the model's parts, as the rest of the app reads them ----------------------
    @property
    def mode(self) -> PoseMode:
        return self.session.mode

    @property
    def scene(self) -> AuthoringScene:
        return self.session.scene

    @property
    def frame(self) -> int:
        return self.session.frame

    @property
    def dirty(self) -> bool:
        return self.session.dirty

    @property
    def selected(self) -> str | None:
        """The joint whose rotation rings are shown: the model's, so undo gives it back."""
        return self.session.selected

    @selected.setter
    def selected(self, joint: str | None) -> None:
        self.session.select(joint)

    # -- layout --------------------------------------------------------------------
    def _dock(self, title: str, widget: QWidget, area: Qt.DockWidgetArea) -> QDockWidget:
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
        return dock

    def _guard(self, title: str, action: Callable[[], Any], warn: bool = False) -> None:
        """Run ``action()``; a UserError becomes a message box titled ``title``, unless the
        window closed while the action waited (a bake cancelled by quitting): a box over
        no window would keep the application running until clicked away."""
        try:
            action()
        except UserError as exc:
            if self.isVisible():
                (QMessageBox.warning if warn else QMessageBox.information)(self, title, str(exc))

    def _edit(self, action: Callable[[], Any]) -> None:
        """A model edit from a gesture: playing stops first; a refused edit says why.
        While a job on the worker reads the pose (a settle), edits wait for it."""
        if self.jobs.running:
            self.statusBar().showMessage("Settling the pose: edits wait until it is done", 3000)
            return
        self.playback.stop()
        self._guard("Pose", action, warn=True)

    def undo_step(self, redo: bool = False) -> None:
        """Undo (or redo) the last step through the model."""
        # a message about the step (a dropped edit's "Ctrl+Z goes back to it") no longer holds
        self.statusBar().clearMessage()
        self._edit(self.session.redo if redo else self.session.undo)

    # -- keys ----------------------------------------------------------------------
    def add_key(self, frame: int) -> None:
        self._edit(lambda: self.session.add_key(frame))

    def delete_key(self, frame: int) -> None:
        self._edit(lambda: self.session.delete_key(frame))

    def move_key(self, frame: int, to: int) -> None:
        def move() -> None:
            if frame != self.frame and self.session.key_at(frame) is not None:
                self.go_to(frame)  # the move starts on its key: the status bar says if an edit is dropped
            self.session.move_key(frame, to)

        self._edit(move)

    def step(self, by: int) -> None:
        """Go ``by`` frames on (or back), within the animation."""
        self.go_to(max(0, min(self.scene.animation.frames - 1, self.frame + by)))

    def step_key(self, by: int) -> None:
        """Go to the next (``by`` > 0) or previous key, if there is one."""
        frames = [k.frame for k in self.scene.keys if (k.frame - self.frame) * by > 0]
        if frames:
            self.go_to(min(frames) if by > 0 else max(frames))

    def go_to(self, frame: int) -> None:
        """Make ``frame`` current (:meth:`engine.authoring.session.AuthoringSession.go_to`);
        between keys the bake comes from the worker first; while the bake plays, go on
        playing from there."""
        if self.playback.playing:
            self.playback.seek(frame)
            return

        def go() -> None:
            if self.session.key_at(int(frame)) is None and self.scene.keys:
                self.playback.baked_scene()
            left = self.session.go_to(frame)
            if left is not None:
                self.statusBar().showMessage(
                    f"The edit of frame {left} was not keyed and is not kept here: Ctrl+Z goes back to it", 10000
                )

        self._guard("Keys", go, warn=True)

    # -- drawing -------------------------------------------------------------------
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
        self.paths.mark_pose(positions)
        self.naturalness.show_pose(positions, self.mode.character.skeleton.offsets)
        self.viewport.plotter.render()

    def _render_soon(self) -> None:
        """One render after the events of an edit (a target changed without the pose)."""
        if not self._render_pending:
            self._render_pending = True
            QTimer.singleShot(0, self._render_now)

    def _render_now(self) -> None:
        self._render_pending = False
        if not getattr(self.viewport.plotter, "_closed", False):
            self.viewport.plotter.render()

    # -- closing -------------------------------------------------------------------
    def close_unasked(self) -> bool:
        """Close without the unsaved-work prompt: the studio's quit has asked it already
        (:func:`app.authoring_actions.confirm_quit`)."""
        self._asked_to_close = True
        return self.close()

    def closeEvent(self, event: QCloseEvent | None) -> None:  # noqa: N802 (Qt's name)
        if event is None:
            return
        if not self._asked_to_close and not self.files.confirm_discard("closing"):
            event.ignore()
            return
        if self.autosave is not None:  # closed on purpose: saved, or discarded when asked
            self.autosave.discard()
        self.jobs.shutdown()
        self.naturalness.stop()
        self.playback.timer.stop()
        self.redraw.close()
        QApplication.instance().removeEventFilter(self.camera_keys)
        if not getattr(self.viewport.plotter, "_closed", False):  # a second close would free VTK twice
            self.viewport.close()
        event.accept()
