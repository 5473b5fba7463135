"""Edit ▸ Re-solve range...: re-solve a frame range of the loaded clip, undoably.

A dialog takes the range (start, end; the range selected on the timeline, when there is
one), the blend frames at each end and what to add:
feet held in floor contact (a ``floor`` constraint) and the scene's own constraints
(each with its own frame range). The solve (:func:`engine.authoring.range_edit.edit_range`,
as an :class:`engine.authoring.jobs.RangeJob` on a copy of the clip) runs on a worker
thread behind a progress dialog with Cancel (:class:`app.job_runner.JobRunner`): the
studio keeps playing and drawing meanwhile. When it ends, the GUI thread replaces the
clip by the result (same path, the frame shown then) as one step on the window's undo
stack, so Ctrl+Z restores the original clip; a cancelled re-solve changes nothing, and
one whose clip was replaced meanwhile is dropped with a message. That replacement
(:func:`replace_clip`) is shared with Edit ▸ Trim clip (:mod:`app.clip_trim`).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import TYPE_CHECKING

from PyQt6.QtGui import QAction
from PyQt6.QtWidgets import QCheckBox, QDialog, QDialogButtonBox, QFormLayout, QMenu, QMessageBox, QSpinBox, QWidget

from app.job_runner import JobRunner
from engine.errors import UserError

if TYPE_CHECKING:
    from app.shell import StudioShell
    from engine.authoring.range_edit import RangeEdit
    from engine.constraints.base import Constraint
    from engine.motion.clip import Motion
    from engine.sensors import Sensor


class RangeDialog(QDialog):
    """Range, blend and what to add; starts on the timeline's selected range, else on
    the current frame."""

    def __init__(
        self, parent: QWidget | None, frames: int, current: int, selection: tuple[int, int] | None = None
    ) -> None:
        super().__init__(parent)
        self.setWindowTitle("Re-solve range")
        form = QFormLayout(self)
        last = max(0, frames - 1)
        start, end = selection if selection is not None else (current, current + 60)
        self.start = QSpinBox(minimum=0, maximum=last, value=min(start, last))
        self.end = QSpinBox(minimum=0, maximum=last, value=min(end, last))
        self.blend = QSpinBox(minimum=0, maximum=120, value=8, suffix=" frames")
        self.floor = QCheckBox("hold feet in floor contact", checked=True)
        self.scene = QCheckBox("the scene's constraints", checked=True)
        for label, w in (
            ("Start", self.start),
            ("End", self.end),
            ("Blend", self.blend),
            ("Add", self.floor),
            ("", self.scene),
        ):
            form.addRow(label, w)
        box = QDialogButtonBox(QDialogButtonBox.StandardButton.Ok | QDialogButtonBox.StandardButton.Cancel)
        box.accepted.connect(self.accept)
        box.rejected.connect(self.reject)
        form.addRow(box)


#: :attr:`ClipState.selection` for an edit that keeps the clip's frames where they are.
KEEP_SELECTION = "keep"


@dataclass(frozen=True)
class ClipState:
    """What an edit of the loaded clip puts on screen, and its undo puts back.

    Attributes
    ----------
    motion : Motion
        The clip (the session's path stays: it is the same clip edited).
    frame : int
        The frame shown (clamped into the clip).
    constraints, sensors : tuple or None
        The scene's constraints and trackers, where the edit moved their frame ranges (a
        trim); None leaves the session's as they are. ``preset`` goes with ``sensors``.
    selection : (int, int), None or KEEP_SELECTION
        The timeline's selection; :data:`KEEP_SELECTION` leaves it (a re-solve keeps its frames).
    """

    motion: Motion
    frame: int
    constraints: tuple[Constraint, ...] | None = None
    sensors: tuple[Sensor, ...] | None = None
    preset: str = ""
    selection: tuple[int, int] | None | str = KEEP_SELECTION


def replace_clip(window: StudioShell, text: str, before: ClipState, after: ClipState) -> None:
    """Show ``after`` and record one undo step named ``text`` that puts ``before`` back.

    The motion is set as the same clip edited (:meth:`app.undo.SceneUndo.same_clip`: the
    history, the camera and the opened clip stay; the engine restarts on it as on a new
    clip, so no ghost, loss or latent of the old frames stays); constraints and sensors
    are part of the same step, not steps of their own."""
    session, path = window.session, window.session.path

    def put(state: ClipState) -> None:
        with window.undo.same_clip():
            session.set_motion(state.motion, path)
        with window.undo.unrecorded():
            if state.sensors is not None:
                session.set_sensors(state.sensors, state.preset)
            if state.constraints is not None:
                session.set_constraints(state.constraints)
        if state.selection != KEEP_SELECTION:
            window.timeline.set_selection(*(state.selection or (None,)))
        session.seek(min(state.frame, len(state.motion) - 1))

    put(after)
    window.undo.record(text, put, before, after)


def range_runner(window: StudioShell) -> JobRunner:
    """The window's runner of range re-solves (made on first use; it cancels its job
    when the window closes)."""
    runner = window.range_jobs
    if runner is None:
        runner = window.range_jobs = JobRunner(window)
        runner.finished.connect(lambda ok, message: _finished(window, ok, message))
        runner.cancel_on_close(window)
    return runner


def resolve_range(
    window: StudioShell, start: int, end: int, blend: int = 8, floor: bool = True, scene: bool = True
) -> JobRunner:
    """Start re-solving ``start..end`` of the window's clip on a worker thread; when it
    ends the result replaces the clip (one undo step). Returns the runner: its
    ``result`` is then the :class:`engine.authoring.range_edit.RangeEdit`, and
    ``wait()`` waits for it with the event loop running."""
    from engine.authoring.jobs import range_job

    session = window.session
    original = session.motion
    job = range_job(original, list(session.constraints) if scene else [], start, end, blend, floor)

    def apply(edit: RangeEdit) -> None:
        if session.motion is not original:
            raise UserError("another clip was opened while the range was re-solved: nothing was replaced")
        frame = session.frame
        replace_clip(
            window, f"re-solve frames {job.start}-{job.end}", ClipState(original, frame), ClipState(edit.motion, frame)
        )

    runner = range_runner(window)
    runner.start(job, apply)
    return runner


def _finished(window: StudioShell, ok: bool, message: str) -> None:
    if ok:
        window.statusBar().showMessage("Range re-solved (Ctrl+Z puts the clip back)", 5000)
    elif message == "cancelled":
        window.statusBar().showMessage("Range re-solve cancelled: the clip is unchanged", 5000)
    else:
        QMessageBox.warning(window, "Re-solve range", message)


def resolve_range_dialog(window: StudioShell) -> None:
    session = window.session
    if session.motion is None:
        QMessageBox.information(window, "Re-solve range", "Open a clip first.")
        return
    dialog = RangeDialog(window, len(session.motion), session.frame, window.timeline.selection())
    window.range_dialog = dialog  # tests answer it
    if dialog.exec() != QDialog.DialogCode.Accepted:
        return
    try:
        resolve_range(
            window,
            dialog.start.value(),
            dialog.end.value(),
            dialog.blend.value(),
            dialog.floor.isChecked(),
            dialog.scene.isChecked(),
        )
    except UserError as exc:
        QMessageBox.warning(window, "Re-solve range", str(exc))


def add_edit_entries(window: StudioShell, edit_menu: QMenu, action: Callable[..., QAction]) -> dict[str, QAction]:
    """Add Re-solve range to ``edit_menu`` with the menus' ``action`` helper."""
    edit_menu.addSeparator()
    return {"resolve_range": action(window, edit_menu, "Re-solve &range...", lambda: resolve_range_dialog(window))}
