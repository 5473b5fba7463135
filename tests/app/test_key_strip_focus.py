"""A click on the pose window's key timeline takes the keyboard focus, so the camera keys
work after a number was typed into a field beside it: left in the length field, the
focus would take a 3 pressed for the side view and make the animation 3 frames long."""

from __future__ import annotations

import pytest
from PyQt6.QtCore import QPoint, Qt
from PyQt6.QtTest import QTest
from PyQt6.QtWidgets import QApplication

pytestmark = pytest.mark.gui


def test_a_camera_key_after_typing_a_length_and_clicking_the_timeline_turns_the_camera(pose_window, qtbot):
    w = pose_window
    w.activateWindow()
    qtbot.waitUntil(lambda: QApplication.activeWindow() is w)
    field = w.keys.length
    QTest.mouseClick(field, Qt.MouseButton.LeftButton)
    field.lineEdit().selectAll()
    QTest.keyClicks(field, "200")
    QTest.keyClick(field, Qt.Key.Key_Return)
    assert w.scene.animation.frames == 200
    strip = w.keys.strip
    QTest.mouseClick(strip, Qt.MouseButton.LeftButton, pos=QPoint(round(strip.x_of(150)), strip.height() // 2))
    assert w.frame == 150
    QTest.keyClick(QApplication.focusWidget(), Qt.Key.Key_3)
    assert w.scene.animation.frames == 200, "the 3 went into the length field"
    assert w.viewport.camera_preset == "side"


@pytest.mark.parametrize("field_name", ["length", "fps", "move_to"])
def test_a_camera_key_right_after_return_in_a_number_field_turns_the_camera(pose_window, qtbot, field_name):
    """Return ends the typing: the field keeps its value and the view takes the keys, so
    a 1 pressed next for the front view does not replace the number (found with xdotool:
    200 typed into the length, Return, then 1 made the animation 1 frame long)."""
    w = pose_window
    w.activateWindow()
    qtbot.waitUntil(lambda: QApplication.activeWindow() is w)
    field = getattr(w.keys, field_name)
    QTest.mouseClick(field, Qt.MouseButton.LeftButton)
    field.lineEdit().selectAll()
    QTest.keyClicks(field, "30")
    QTest.keyClick(field, Qt.Key.Key_Return)
    qtbot.waitUntil(lambda: QApplication.focusWidget() is not field)
    QTest.keyClick(QApplication.focusWidget(), Qt.Key.Key_1)
    assert field.value() == 30
    assert w.viewport.camera_preset == "front"


@pytest.mark.parametrize(("field_name", "typed", "value"), [("length", "200", 200), ("fps", "24", 24.0)])
def test_a_number_typed_into_the_length_or_rate_is_one_edit(pose_window, qtbot, field_name, typed, value):
    """The number is taken when typing ends (Return), as one undo step: taken digit by
    digit, 200 typed into the length made the animation 2, then 20, then 200 frames long
    (three undo steps, found with xdotool), and a key past frame 2 lay outside it while
    the 0s were typed."""
    w = pose_window
    field = getattr(w.keys, field_name)
    steps = w.undo.count()
    seen = []
    signal = w.keys.lengthChanged if field_name == "length" else w.keys.fpsChanged
    signal.connect(seen.append)
    QTest.mouseClick(field, Qt.MouseButton.LeftButton)
    field.lineEdit().selectAll()
    QTest.keyClicks(field, typed)
    assert seen == []
    QTest.keyClick(field, Qt.Key.Key_Return)
    assert seen == [value]
    assert w.undo.count() == steps + 1
    attr = "frames" if field_name == "length" else "fps"
    assert getattr(w.scene.animation, attr) == value
