"""The camera keys (Home, 1, 3, 7) work wherever the keyboard focus is in the window."""

from __future__ import annotations

import pytest
from PyQt6.QtCore import Qt
from PyQt6.QtGui import QCursor
from PyQt6.QtTest import QTest
from PyQt6.QtWidgets import QApplication

pytestmark = pytest.mark.gui

KEYS = ((Qt.Key.Key_7, "top"), (Qt.Key.Key_Home, "home"), (Qt.Key.Key_3, "side"), (Qt.Key.Key_1, "front"))


def _focus_targets(studio):
    weight = next(iter(studio.sensor_panel.rows.values()))["weight"]
    return {"window": studio, "3D view": studio.viewport.plotter, "timeline slider": studio.timeline.slider,
            "sensor weight": weight, "fail frames": studio.sensor_panel.fail_frames,
            "preset": studio.sensor_panel.preset}  # fmt: skip


def test_camera_keys_work_over_the_view_whatever_has_the_focus(studio, qtbot):
    studio.windowHandle().requestActivate()
    qtbot.waitUntil(lambda: QApplication.activeWindow() is studio)
    view = studio.viewport
    QCursor.setPos(view.mapToGlobal(view.rect().center()))
    qtbot.waitUntil(lambda: studio.camera_keys.pointer_over_view())
    failed = []
    for name, widget in _focus_targets(studio).items():
        widget.setFocus()
        QApplication.processEvents()
        for key, preset in KEYS:
            studio.viewport.set_camera("home" if preset != "home" else "front")
            QTest.keyClick(QApplication.focusWidget() or studio, key)
            if studio.viewport.camera_preset != preset:
                failed.append(f"{key.name} with {name} focused")
    assert not failed, failed


def test_a_number_field_keeps_its_digits_away_from_the_view(studio, qtbot):
    studio.windowHandle().requestActivate()
    qtbot.waitUntil(lambda: QApplication.activeWindow() is studio)
    field = studio.sensor_panel.fail_frames
    QCursor.setPos(field.mapToGlobal(field.rect().center()))
    qtbot.waitUntil(lambda: not studio.camera_keys.pointer_over_view())
    field.setFocus()
    field.selectAll()
    studio.viewport.set_camera("home")
    QTest.keyClicks(field, "37")
    assert field.text().startswith("37") and studio.viewport.camera_preset == "home"
