"""The camera keys (Home, 1, 3, 7) work wherever the keyboard focus is, except in a field
the user types into, which keeps its digits wherever the pointer rests."""

from __future__ import annotations

import pytest
from PyQt6.QtCore import Qt
from PyQt6.QtGui import QCursor
from PyQt6.QtTest import QTest
from PyQt6.QtWidgets import QApplication

pytestmark = pytest.mark.gui

KEYS = ((Qt.Key.Key_7, "top"), (Qt.Key.Key_Home, "home"), (Qt.Key.Key_3, "side"), (Qt.Key.Key_1, "front"))


def _activate(studio, qtbot, pointer_on):
    studio.windowHandle().requestActivate()
    qtbot.waitUntil(lambda: QApplication.activeWindow() is studio)
    QCursor.setPos(pointer_on.mapToGlobal(pointer_on.rect().center()))


def test_camera_keys_work_whatever_panel_widget_has_the_focus(studio, qtbot):
    row = next(iter(studio.sensor_panel.rows.values()))
    _activate(studio, qtbot, studio.sensor_panel)  # the pointer away from the 3D view
    targets = {
        "window": studio,
        "3D view": studio.viewport.plotter,
        "timeline slider": studio.timeline.slider,
        "preset": studio.sensor_panel.preset,
        "sensor toggle": row["enabled"],
    }
    failed = []
    for name, widget in targets.items():
        widget.setFocus()
        QApplication.processEvents()
        for key, preset in KEYS:
            studio.viewport.set_camera("home" if preset != "home" else "front")
            QTest.keyClick(QApplication.focusWidget() or studio, key)
            if studio.viewport.camera_preset != preset:
                failed.append(f"{key.name} with {name} focused")
    assert not failed, failed


@pytest.mark.parametrize("field", ["fail frames", "iterations"])
def test_a_number_field_keeps_its_digits_even_with_the_pointer_over_the_view(studio, qtbot, field):
    _activate(studio, qtbot, studio.viewport)
    widget = {
        "fail frames": studio.sensor_panel.fail_frames,
        "iterations": studio.optimizer_panel.editors["iterations"],
    }[field]
    widget.setFocus()
    QApplication.processEvents()
    widget.selectAll()
    studio.viewport.set_camera("home")
    QTest.keyClicks(widget, "37")
    assert widget.text().startswith("37") and studio.viewport.camera_preset == "home"


def test_escape_leaves_a_number_field_and_the_camera_keys_work_again(studio, qtbot):
    _activate(studio, qtbot, studio.viewport)
    field = studio.sensor_panel.fail_frames
    field.setFocus()
    QApplication.processEvents()
    QTest.keyClick(field, Qt.Key.Key_Escape)
    assert not field.hasFocus()
    studio.viewport.set_camera("home")
    QTest.keyClick(QApplication.focusWidget() or studio, Qt.Key.Key_7)
    assert studio.viewport.camera_preset == "top"
