"""Constraint frame ranges in both windows' constraint editors: set with real clicks and
typed numbers, undone, and drawn on the window's timeline as a span of the gizmos' cyan."""

from __future__ import annotations

import numpy as np
import pytest
from PyQt6.QtCore import Qt
from PyQt6.QtTest import QTest
from PyQt6.QtWidgets import QApplication, QTabWidget

from tests.app.gui_helpers import ctrl_drag_pin, type_number

pytestmark = pytest.mark.gui


def cyan_columns(widget, top: int, bottom: int) -> np.ndarray:
    """x of the columns of ``widget``'s rows ``top..bottom`` holding the gizmos' cyan."""
    img = widget.grab().toImage()
    img = img.convertToFormat(img.Format.Format_RGB888)
    w, h = img.width(), img.height()
    arr = np.frombuffer(img.constBits().asstring(img.bytesPerLine() * h), np.uint8)
    arr = arr.reshape(h, img.bytesPerLine())[:, : 3 * w].reshape(h, w, 3).astype(int)[top:bottom]
    cyan = (arr[..., 0] < 80) & (arr[..., 1] > 170) & (arr[..., 2] > 200)
    return np.flatnonzero(cyan.any(axis=0))


def test_a_ctrl_dragged_pin_is_limited_to_a_range_on_the_paused_studio_and_undone(studio, qtbot, monkeypatch):
    monkeypatch.setattr("engine.authoring.history.MERGE_S", 0.0)  # a user's edits come seconds apart: none merge
    s, panel = studio.session, studio.constraint_panel
    pin = ctrl_drag_pin(studio, qtbot)
    assert pin.kind == "pin" and pin.frames is None
    tabs = panel.parentWidget()
    while not isinstance(tabs, QTabWidget):
        tabs = tabs.parentWidget()
    tabs.setCurrentWidget(panel)
    qtbot.waitUntil(lambda: panel.editor is not None and panel.editor.range is not None)
    rng = panel.editor.range
    assert rng.isVisible() and not rng.limited.isChecked() and not rng.start.isEnabled()
    assert studio.timeline.slider.span() is None

    steps = studio.undo.history.count()
    QTest.mouseClick(rng.limited, Qt.MouseButton.LeftButton, pos=rng.limited.rect().center())
    assert s.constraints[0].frames == (20, 80)  # 30 frames either side of the paused frame
    type_number(panel.editor.range.start, 40)
    type_number(panel.editor.range.end, 70)
    type_number(panel.editor.range.blend_out, 6)
    c = s.constraints[0]
    assert (c.frames, c.blend_in, c.blend_out) == ((40, 70), 0, 6)
    assert c.activity(39) == 0.0 and c.activity(55) == 1.0 and 0 < c.activity(73) < 1 and c.activity(77) == 0.0
    assert studio.undo.history.count() == steps + 4  # each edit one undo step

    slider = studio.timeline.slider
    assert slider.span() == (40, 70, 0, 6)
    cols = cyan_columns(slider, 0, 4)
    x40, x70, x76 = slider.point_of(40).x(), slider.point_of(70).x(), slider.point_of(76).x()
    assert cols.size and abs(cols.min() - x40) <= 2 and x70 <= cols.max() <= x76 + 2, (cols.min(), cols.max())

    for _ in range(4):
        studio.undo.history.undo()
    assert s.constraints[0].frames is None and s.constraints[0].blend_out == 0
    qtbot.waitUntil(lambda: not panel.editor.range.limited.isChecked())
    assert slider.span() is None and cyan_columns(slider, 0, 4).size == 0


def test_the_pose_window_edits_a_constraint_range_shows_it_on_the_key_strip_and_undoes(pose_window, qtbot, monkeypatch):
    monkeypatch.setattr("engine.authoring.history.MERGE_S", 0.0)  # a user's edits come seconds apart
    w = pose_window
    panel = w.constraints.panel
    w.keys.length.setValue(200)
    w.go_to(130)
    panel.kinds.setCurrentText("pin")
    QTest.mouseClick(panel.add_button, Qt.MouseButton.LeftButton)
    assert [c.kind for c in w.session.mode.constraints] == ["pin"]
    rng = panel.editor.range
    QTest.mouseClick(rng.limited, Qt.MouseButton.LeftButton, pos=rng.limited.rect().center())
    assert w.session.mode.constraints[0].frames == (100, 160)  # frames 100-160 around frame 130
    type_number(panel.editor.range.blend_in, 10)
    c = w.session.mode.constraints[0]
    assert (c.frames, c.blend_in) == ((100, 160), 10)

    strip = w.keys.strip
    assert strip.span == (100, 160, 10, 0)
    cols = cyan_columns(strip, strip.height() - 5, strip.height() - 1)
    assert cols.size and abs(cols.min() - strip.x_of(90)) <= 2 and abs(cols.max() - strip.x_of(160)) <= 3

    w.windowHandle().requestActivate()  # window shortcuts need the active window
    qtbot.waitUntil(lambda: QApplication.activeWindow() is w)
    w.viewport.plotter.setFocus()  # out of the number field, whose own Ctrl+Z undoes typing
    QTest.keyClick(w.viewport, Qt.Key.Key_Z, Qt.KeyboardModifier.ControlModifier)
    assert w.session.mode.constraints[0].blend_in == 0
    QTest.keyClick(w.viewport, Qt.Key.Key_Z, Qt.KeyboardModifier.ControlModifier)
    assert w.session.mode.constraints[0].frames is None
    assert not panel.editor.range.limited.isChecked() and strip.span is None


def test_the_frame_range_span_is_drawn_only_for_the_selected_constraint(studio, qtbot):
    s, panel = studio.session, studio.constraint_panel
    s.constraints.add("floor", name="floor")
    s.constraints.add("pin", name="held", joint="lwrist", position=np.array([0.3, -0.2, 1.2]))
    s.constraints.edit("held", frames=(10, 30), blend_in=5)
    qtbot.waitUntil(lambda: panel.current_name() == "held")
    assert studio.timeline.slider.span() == (10, 30, 5, 0)
    panel.list.setCurrentRow(0)  # the floor acts on every frame
    assert studio.timeline.slider.span() is None


def test_the_range_fields_reach_the_last_frame_of_a_lengthened_animation(pose_window, qtbot):
    w = pose_window
    panel = w.constraints.panel
    panel.kinds.setCurrentText("floor")
    QTest.mouseClick(panel.add_button, Qt.MouseButton.LeftButton)
    assert panel.editor.range.end.maximum() == 60  # the 61 frames of a new animation
    w.keys.length.setValue(300)
    assert panel.editor.range.end.maximum() == 299
