"""Undo and redo give the rotation rings back to the joint selected before the step,
drawn where it is then (real mouse events on the view, Ctrl+Z and Ctrl+Shift+Z): a
drag that selected the wrist and is undone leaves the rings on the elbow clicked before
it, not on the wrist the undo took the target from."""

from __future__ import annotations

import numpy as np
import pytest
from PyQt6.QtCore import Qt
from PyQt6.QtTest import QTest
from PyQt6.QtWidgets import QApplication

from engine import skeleton as sk
from tests.app.gui_helpers import mouse_drag, pixel_of
from tests.app.test_pose_selection import click

pytestmark = pytest.mark.gui
LW, LE = sk.JOINT_INDEX["lwrist"], sk.JOINT_INDEX["lelbow"]
UNDO, REDO = (
    Qt.KeyboardModifier.ControlModifier,
    Qt.KeyboardModifier.ControlModifier | Qt.KeyboardModifier.ShiftModifier,
)


def key(w, mods) -> None:
    QTest.keyClick(QApplication.focusWidget() or w, Qt.Key.Key_Z, mods)
    QApplication.processEvents()


def rings_on(w, joint: str | None) -> bool:
    """Whether the rings are shown on ``joint`` where the pose has it, drawn there (None: hidden)."""
    rings = w.viewport.rings
    if joint is None:
        return not rings.visible and not any(a.GetVisibility() for a in rings.actors)
    at = w.mode.pose.positions[sk.JOINT_INDEX[joint]]
    drawn = np.mean(rings.meshes[2].points, axis=0)
    return bool(rings.visible and np.allclose(rings.center, at) and np.allclose(drawn, at, atol=1e-6))


@pytest.fixture
def window(pose_window, qtbot):
    w = pose_window
    w.activateWindow()
    qtbot.waitUntil(lambda: QApplication.activeWindow() is w)
    w.viewport.plotter.render()
    return w


def test_undoing_a_drag_gives_the_rings_back_to_the_joint_selected_before_it(window):
    w = window
    view = w.viewport
    click(view, *pixel_of(view, w.mode.pose.positions[LE]))
    assert w.selected == "lelbow" and rings_on(w, "lelbow")
    x, y = pixel_of(view, w.mode.pose.positions[LW])
    mouse_drag(view, (x, y), (x + 50, y + 90), steps=6)
    assert w.selected == "lwrist" and rings_on(w, "lwrist") and "lwrist" in w.mode.targets
    key(w, UNDO)
    assert w.mode.targets == {}
    assert w.selected == "lelbow" and rings_on(w, "lelbow"), w.selected
    assert w.paths.selected == "lelbow"
    key(w, REDO)
    assert "lwrist" in w.mode.targets and w.selected == "lwrist" and rings_on(w, "lwrist")


def test_undo_with_nothing_selected_before_hides_the_rings_and_a_turn_keeps_them(window):
    w = window
    view = w.viewport
    x, y = pixel_of(view, w.mode.pose.positions[LW])
    mouse_drag(view, (x, y), (x + 50, y + 90), steps=6)
    assert w.selected == "lwrist" and rings_on(w, "lwrist")
    key(w, UNDO)
    assert w.selected is None and rings_on(w, None)
    # a click selects the wrist (no step); its ring turned and undone: the rings stay on it, where it is
    click(view, *pixel_of(view, w.mode.pose.positions[LW]))
    assert w.selected == "lwrist"
    view.plotter.render()
    ring = view.joints._to_display(view.rings.meshes[2].points)
    far = ring[np.argmax(np.linalg.norm(ring - pixel_of(view, view.rings.center), axis=1))]
    mouse_drag(view, tuple(far), (far[0] + 25, far[1] + 25), steps=5)
    assert w.undo.undo_text() == "turn lwrist"
    key(w, UNDO)
    assert w.selected == "lwrist" and rings_on(w, "lwrist")
