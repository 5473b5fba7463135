"""Edit ▸ Re-solve range...: re-solve a frame range of the loaded clip, undoably.

A dialog takes the range (start, end; the range selected on the timeline, when there is
one), the blend frames at each end and what to add:
feet held in floor contact (a ``floor`` constraint) and the scene's own constraints
(each with its own frame range). :func:`engine.authoring.range_edit.edit_range` solves
it; the clip is replaced by the result (same path, same frame) and the replacement is
one step on the window's undo stack, so Ctrl+Z restores the original clip.
"""

from __future__ import annotations

from typing import Any

from PyQt6.QtWidgets import QCheckBox, QDialog, QDialogButtonBox, QFormLayout, QMenu, QMessageBox, QSpinBox

from app.undo import StateCommand
from engine.errors import UserError


class RangeDialog(QDialog):
    """Range, blend and what to add; starts on the timeline's selected range, else on
    the current frame."""

    def __init__(self, parent: Any, frames: int, current: int, selection: tuple[int, int] | None = None) -> None:
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
        for label, w in (("Start", self.start), ("End", self.end), ("Blend", self.blend), ("Add", self.floor),
                         ("", self.scene)):  # fmt: skip
            form.addRow(label, w)
        box = QDialogButtonBox(QDialogButtonBox.StandardButton.Ok | QDialogButtonBox.StandardButton.Cancel)
        box.accepted.connect(self.accept)
        box.rejected.connect(self.reject)
        form.addRow(box)


def resolve_range(window: Any, start: int, end: int, blend: int = 8, floor: bool = True, scene: bool = True):
    """Re-solve ``start..end`` of the window's clip and replace it (one undo step);
    returns the :class:`engine.authoring.range_edit.RangeEdit`."""
    from engine.authoring.range_edit import edit_range
    from engine.constraints import FloorConstraint
    from engine.models import load_default_models

    session = window.session
    original, path, frame = session.motion, session.path, session.frame
    if original is None:
        raise UserError("open a clip first")
    constraints = list(session.constraints) if scene else []
    if floor:
        constraints.append(FloorConstraint(name="range floor"))
    edit = edit_range(load_default_models().vae, original, int(start), int(end), constraints, int(blend))

    def show(motion) -> None:
        with window.undo.same_clip():
            session.set_motion(motion, path)
        session.seek(min(frame, len(motion) - 1))

    show(edit.motion)
    window.undo.stack.push(StateCommand(f"re-solve frames {start}-{end}", show, original, edit.motion))
    return edit


def resolve_range_dialog(window: Any) -> None:
    session = window.session
    if session.motion is None:
        QMessageBox.information(window, "Re-solve range", "Open a clip first.")
        return
    dialog = RangeDialog(window, len(session.motion), session.frame, window.timeline.selection())
    window.range_dialog = dialog  # tests answer it
    if dialog.exec() != QDialog.DialogCode.Accepted:
        return
    try:
        resolve_range(window, dialog.start.value(), dialog.end.value(), dialog.blend.value(),
                      dialog.floor.isChecked(), dialog.scene.isChecked())  # fmt: skip
    except UserError as exc:
        QMessageBox.warning(window, "Re-solve range", str(exc))


def add_edit_entries(window: Any, edit_menu: QMenu, action) -> dict:
    """Add Re-solve range to ``edit_menu`` with the menus' ``action`` helper."""
    edit_menu.addSeparator()
    return {"resolve_range": action(window, edit_menu, "Re-solve &range...", lambda: resolve_range_dialog(window))}
