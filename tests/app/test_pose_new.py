"""File ▸ New pose in the pose window (Ctrl+Shift+N, a real key press): with unsaved keys
it asks first and Cancel keeps everything; Discard, then the height typed into the New
pose dialog and its OK clicked, leaves an empty document in the same window: no keys,
targets or constraints, the character of that height standing in the mean pose, nothing
to undo and nothing unsaved."""

from __future__ import annotations

import numpy as np
import pytest
from PyQt6.QtCore import Qt, QTimer
from PyQt6.QtTest import QTest
from PyQt6.QtWidgets import QApplication, QDialogButtonBox, QMessageBox

from engine import skeleton as sk
from tests.app.gui_helpers import drag_wrist, scrub, shortcut

pytestmark = pytest.mark.gui

CTRL_SHIFT = Qt.KeyboardModifier.ControlModifier | Qt.KeyboardModifier.ShiftModifier


@pytest.fixture
def asked(monkeypatch):
    """The unsaved-changes prompts (their text), answered with ``asked.answer``."""

    class Asked(list):
        answer = QMessageBox.StandardButton.Cancel

    prompts = Asked()

    def question(parent, title, text, buttons):
        prompts.append(text)
        return prompts.answer

    monkeypatch.setattr(QMessageBox, "question", question)
    return prompts


def fill_new_pose_dialog(height: str, seen: list) -> None:
    """When the New pose dialog is up: type ``height`` (metres) and click OK."""

    def fill() -> None:
        dialog = QApplication.activeModalWidget()
        if dialog is None or dialog.windowTitle() != "New pose":
            QTimer.singleShot(20, fill)
            return
        seen.append(dialog.start.count())
        spin = dialog.height_m
        spin.setFocus()
        spin.selectAll()
        QTest.keyClicks(spin, height)
        ok = dialog.findChild(QDialogButtonBox).button(QDialogButtonBox.StandardButton.Ok)
        QTest.mouseClick(ok, Qt.MouseButton.LeftButton)

    QTimer.singleShot(0, fill)


def test_new_pose_asks_about_unsaved_keys_then_starts_an_empty_pose(pose_window, asked, qtbot):
    w = pose_window
    w.activateWindow()
    qtbot.waitUntil(lambda: QApplication.activeWindow() is w)
    (file_menu,) = [a.menu() for a in w.menuBar().actions() if a.text() == "&File"]
    (entry,) = [a for a in file_menu.actions() if a.text() == "&New pose..."]
    assert entry.shortcut().toString() == "Ctrl+Shift+N"
    w.actions_by_name["camera-front"].trigger()
    standing = w.mode.pose.positions.copy()
    w.keys.add.click()
    scrub(w, 40)
    drag_wrist(w)
    w.keys.add.click()
    w.session.add_constraint("floor")
    assert [k.frame for k in w.scene.keys] == [0, 40] and w.dirty and w.mode.targets

    w.viewport.plotter.setFocus()
    shortcut(w, Qt.Key.Key_N, CTRL_SHIFT)
    assert len(asked) == 1 and "before starting a new pose" in asked[0]
    assert [k.frame for k in w.scene.keys] == [0, 40] and w.dirty, "Cancel keeps the keys"

    asked.answer = QMessageBox.StandardButton.Discard
    seen: list[int] = []
    fill_new_pose_dialog("1.60", seen)
    shortcut(w, Qt.Key.Key_N, CTRL_SHIFT)
    assert len(asked) == 2 and seen == [1], "the dialog offers the neutral pose only"
    assert w.scene.keys == [] and w.mode.targets == {} and w.mode.constraints == []
    assert w.frame == 0 and not w.dirty and not w.undo.can_undo()
    assert w.mode.character.height == pytest.approx(1.60, abs=1e-6) and w.scene.height == pytest.approx(1.60)
    assert w.files.path is None and w.keys.strip.keys == ()
    wrist = sk.JOINT_INDEX["lwrist"]
    scale = 1.60 / 1.75
    assert np.linalg.norm(w.mode.pose.positions[wrist] - standing[wrist] * scale) < 0.05, "standing, hands down"
    assert not w.viewport.gizmos.items and "New pose" in w.statusBar().currentMessage()

    fill_new_pose_dialog("1.75", seen)
    shortcut(w, Qt.Key.Key_N, CTRL_SHIFT)  # nothing unsaved: no question, straight to the dialog
    assert len(asked) == 2 and len(seen) == 2
    assert w.mode.character.height == pytest.approx(1.75, abs=1e-6)
