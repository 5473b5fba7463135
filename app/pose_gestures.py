"""The pose window's gestures on the body (:class:`PoseGestures`, a base of
:class:`app.pose_window.PoseWindow`).

A press or click on a joint selects it (its rotation rings and its motion path show); a
drag on a joint or its target moves the target (a wrist or an ankle at the depth
:mod:`engine.authoring.drag_reach` gives; with Alt the joint turns, with Shift on the
hips the pelvis moves alone; a pin holding the joint on the frame moves with it, and the
status bar names it); the body is moved and turned, the target list's edits are applied
and the settle runs on a worker. Each gesture is one call on the authoring model
(:class:`engine.authoring.session.AuthoringSession`), through the window's ``_edit``.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import TYPE_CHECKING, Any

import numpy as np
from PyQt6.QtCore import Qt
from PyQt6.QtWidgets import QApplication, QMessageBox

from app.job_runner import JobRunner
from engine.authoring.drag_reach import limb_reach, on_reach, onto_body
from engine.authoring.pose_mode import PoseMode
from engine.authoring.session import AuthoringSession

if TYPE_CHECKING:
    from PyQt6.QtWidgets import QStatusBar

    from app.motion_path_view import MotionPathView
    from app.pose_timeline import KeyPlayback
    from app.pose_turns import JointTurns
    from widgets.viewport.viewport import Viewport


class PoseGestures:
    """The gestures of the pose window on the body and its targets (see the module doc);
    the window holds the parts they use, declared here."""

    session: AuthoringSession
    viewport: Viewport
    turns: JointTurns
    paths: MotionPathView
    playback: KeyPlayback
    jobs: JobRunner
    selected: str | None
    #: The joint pressed and its limb as it was at the press: a dragged wrist or ankle
    #: takes the depth its limb's stretch asks for (:mod:`engine.authoring.drag_reach`).
    _reach: tuple[str, tuple[np.ndarray, float]] | None

    if TYPE_CHECKING:

        @property
        def mode(self) -> PoseMode: ...

        def statusBar(self) -> QStatusBar: ...  # noqa: N802 (Qt's name)

        def isVisible(self) -> bool: ...  # noqa: N802 (Qt's name)

        def _edit(self, action: Callable[[], Any]) -> None: ...

        def _render_soon(self) -> None: ...

    def select(self, joint: str) -> None:
        """Select ``joint`` (a press or click on it, or on its target): its rotation rings
        and its motion path show."""
        self.session.select(joint, pressed=self.viewport.mouse_held)
        limb = limb_reach(self.mode.pose.positions, joint)
        self._reach = None if limb is None else (joint, limb)
        self.turns.show_handles()
        self.paths.select(joint)
        self._render_soon()

    def _placed(self, joint: str, point: np.ndarray, pressed: np.ndarray, *ray_and_normal: np.ndarray) -> np.ndarray:
        """Where a drag of ``joint`` pressed at ``pressed`` to ``point`` on its drag plane
        puts it (:func:`engine.authoring.drag_reach.on_reach` for a wrist or an ankle)."""
        if self._reach is None or self._reach[0] != joint or self._alt_held():
            return point  # an Alt-drag turns the joint by the mouse's direction on the plane
        placed = on_reach(point, pressed, *ray_and_normal, *self._reach[1])
        touched = onto_body(placed, ray_and_normal[1], self.mode.pose.positions, joint)
        return placed if touched is None else touched

    def _alt_held(self) -> bool:
        """Whether Alt is held with the drag (:meth:`_held_with_drag`)."""
        return self._held_with_drag(Qt.KeyboardModifier.AltModifier)

    def _held_with_drag(self, key: Qt.KeyboardModifier) -> bool:
        """Whether modifier ``key`` is held with the drag: the keys of the mouse event that
        moved it (:attr:`widgets.viewport.viewport.Viewport.drag_modifiers`), else (a drag
        not made by the mouse) the keys held now, asked of the system: Qt's cached
        modifiers lag until its next input event (an Alt pressed before the drag read as
        none)."""
        held = self.viewport.drag_modifiers
        if held is None:
            held = QApplication.queryKeyboardModifiers()
        return bool(held & key)

    def drag_joint(self, joint: str, position: np.ndarray) -> None:
        """Create or move the target on ``joint`` to ``position (3,)`` metres and solve (a
        pin holding the joint on this frame moves with it, and the status bar names it);
        with Alt held, turn it instead (:meth:`app.pose_turns.JointTurns.alt_drag`)."""
        self.selected = joint
        self.paths.select(joint)
        if self._alt_held():
            self.turns.alt_drag(joint, position)
            return
        self.turns.gesture = None
        if joint == "root" and self._held_with_drag(Qt.KeyboardModifier.ShiftModifier):
            self.statusBar().showMessage("Pelvis only: feet planted", 2000)
            self._edit(lambda: self.session.drag_pelvis(np.asarray(position, float)))
        else:
            pin = self.session.holding_pin(joint)
            if pin is not None:
                self.statusBar().showMessage(f"{joint} is held by pin {pin.name!r} here: the drag moves the pin", 3000)
            self._edit(lambda: self.session.drag_joint(joint, np.asarray(position, float)))
        self.turns.show_handles()  # the grabbed joint is selected even when nothing moved
        self._render_soon()

    def deselect(self) -> None:
        """Hide the rotation rings (and the selected joint's motion path)."""
        self.selected = None
        self.turns.show_handles()
        self.paths.select(None)
        self._render_soon()

    def move_body(self, delta: np.ndarray) -> None:
        self._edit(lambda: self.session.move_body(delta))

    def turn_body(self, heading: float) -> None:
        self._edit(lambda: self.session.turn_body(heading))

    def edit_target(self, joint: str, **fields: Any) -> None:
        """Change a target's ``enabled`` or ``weight`` and solve."""
        self._edit(lambda: self.session.edit_target(joint, **fields))

    def clear_target(self, joint: str) -> None:
        self._edit(lambda: self.session.clear_target(joint))

    def clear_all(self) -> None:
        self._edit(self.session.clear_all)

    def settle(self) -> JobRunner:
        """An offline solve of the current targets (one undo step), on a worker: it takes
        seconds with constraints on a loaded machine, and the window keeps drawing and
        answering meanwhile (a window-modal progress dialog with Cancel keeps edits out);
        the result is applied here, on the GUI thread. Returns the runner (``wait()``
        waits for the result with the event loop running)."""
        if self.jobs.running:
            return self.jobs
        self.playback.stop()
        job = self.session.settle_job()

        def done(ok: bool, message: str) -> None:
            self.jobs.finished.disconnect(done)
            if not ok and message != "cancelled" and self.isVisible():
                QMessageBox.warning(self, "Settle pose", message)

        self.jobs.finished.connect(done)
        self.jobs.start(job, lambda settled: self.session.take_settle(job, settled), modal=True)
        return self.jobs
