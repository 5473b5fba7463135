"""Switching the reconstruction method in the Optimizer tab is an undo step: Ctrl+Z brings
the previous method back (the combo box and the engine follow) on the scene as it was,
Ctrl+Shift+Z switches again; ghosts likewise."""

from __future__ import annotations

import numpy as np
import pytest
from PyQt6.QtCore import Qt
from PyQt6.QtWidgets import QApplication

pytestmark = pytest.mark.gui


def scene_of(s) -> tuple:
    return (
        s.preset,
        tuple((j, bool(x.enabled), tuple(np.round(x.offset, 9))) for j, x in s.sensors.items()),
        tuple(c.name for c in s.constraints),
        dict(s.settings),
    )


def test_a_method_switch_is_undone_and_redone_from_the_keyboard_with_the_scene_intact(studio, qtbot):
    from PyQt6.QtTest import QTest

    s, stack, panel = studio.session, studio.undo.history, studio.optimizer_panel
    studio.viewport.jointDragged.emit("lelbow", np.array([0.4, 0.0, 1.3]))  # a pin: a scene to keep
    panel.editors["lr"].stepBy(1)
    stack.clear()
    assert s.method == "ik" and panel.method.currentText() == "ik"
    scene = scene_of(s)
    panel.method.setCurrentText("dragposer")  # the user's choice in the combo box
    assert s.method == "dragposer" and stack.count() == 1 and stack.undo_text() == "Method dragposer"
    undo = next(a for a in studio.findChildren(type(studio.menuBar().actions()[0])) if a.text().startswith("&Undo"))
    assert undo.isEnabled() and undo.text() == "&Undo Method dragposer"
    studio.windowHandle().requestActivate()
    qtbot.waitUntil(lambda: QApplication.activeWindow() is studio)
    QTest.keyClick(studio.viewport, Qt.Key.Key_Z, Qt.KeyboardModifier.ControlModifier)
    assert s.method == "ik" and panel.method.currentText() == "ik" and scene_of(s) == scene
    qtbot.waitUntil(
        lambda: s.latest is not None and s.latest.method == "ik" and not s.latest.method_error, timeout=30000
    )
    QTest.keyClick(
        studio.viewport, Qt.Key.Key_Z, Qt.KeyboardModifier.ControlModifier | Qt.KeyboardModifier.ShiftModifier
    )
    assert s.method == "dragposer" and panel.method.currentText() == "dragposer" and scene_of(s) == scene
    qtbot.waitUntil(lambda: s.latest.method == "dragposer" and not s.latest.method_error, timeout=60000)
    # a ghost ticked is a step of its own, undone to none
    panel.ghost_boxes["ik"].click()
    assert s.ghosts == ("ik",) and stack.undo_text() == "Ghosts ik"
    stack.undo()
    assert s.ghosts == () and s.method == "dragposer" and not panel.ghost_boxes["ik"].isChecked()
