"""A frame range selected on the studio's timeline: Shift-click, Shift-drag, the band, the dialog."""

from __future__ import annotations

import pytest

pytestmark = pytest.mark.gui


def _shift_press(slider, frame: int):
    from PyQt6.QtCore import Qt
    from PyQt6.QtTest import QTest

    QTest.mousePress(slider, Qt.MouseButton.LeftButton, Qt.KeyboardModifier.ShiftModifier, slider.point_of(frame))


def test_shift_click_and_shift_drag_select_a_range_and_right_click_clears(studio, qtbot):
    from PyQt6.QtCore import Qt
    from PyQt6.QtTest import QTest

    slider = studio.timeline.slider
    studio.session.seek(30)
    qtbot.waitUntil(lambda: slider.value() == 30)
    seen = []
    studio.timeline.selectionChanged.connect(lambda a, b: seen.append((a, b)))
    _shift_press(slider, 50)  # a click: from the current frame to the clicked one
    QTest.mouseRelease(slider, Qt.MouseButton.LeftButton, Qt.KeyboardModifier.ShiftModifier, slider.point_of(50))
    assert studio.timeline.selection() == (30, 50) and seen[-1] == (30, 50)
    assert studio.session.frame == 30 and slider.value() == 30  # a Shift-click does not scrub
    _shift_press(slider, 70)  # a drag: the frames swept, either direction
    QTest.mouseMove(slider, slider.point_of(60))
    QTest.mouseMove(slider, slider.point_of(10))
    QTest.mouseRelease(slider, Qt.MouseButton.LeftButton, Qt.KeyboardModifier.ShiftModifier, slider.point_of(10))
    assert studio.timeline.selection() == (10, 70)
    QTest.mouseClick(slider, Qt.MouseButton.RightButton, pos=slider.point_of(40))
    assert studio.timeline.selection() is None and seen[-1] == (-1, -1)


def test_the_band_is_drawn_over_the_selected_frames(studio, qtbot):
    slider = studio.timeline.slider
    before = slider.grab().toImage()
    studio.timeline.set_selection(20, 60)
    img = slider.grab().toImage()
    y = slider.height() // 2
    x_in, x_out = slider.point_of(40).x(), slider.point_of(len(studio.session.motion) - 5).x()

    def orange(image, x):
        c = image.pixelColor(x, y + 4)
        return c.red() > c.blue() + 40

    assert orange(img, x_in) and not orange(before, x_in)
    assert not orange(img, x_out)


def test_the_range_dialog_starts_on_the_selection_and_the_resolve_is_unsaved(studio, qtbot):
    from PyQt6.QtCore import QTimer

    from app.range_actions import resolve_range_dialog

    assert studio.undo.is_clean()
    studio.timeline.set_selection(24, 44)
    seen = {}

    def answer():
        d = studio.range_dialog
        seen["range"] = (d.start.value(), d.end.value())
        d.blend.setValue(4)
        d.accept()

    QTimer.singleShot(0, answer)
    original = studio.session.motion
    resolve_range_dialog(studio)
    studio.range_jobs.wait()  # the re-solve runs on a worker
    assert seen["range"] == (24, 44)
    assert studio.session.motion is not original
    assert not studio.undo.is_clean()  # the re-solve is an unsaved edit
    assert studio.timeline.selection() == (24, 44)  # the edited clip keeps its selection
    studio.undo.history.undo()
    assert studio.session.motion is original and studio.undo.is_clean()
    qtbot.waitUntil(lambda: studio.session.latest is not None, timeout=10000)
