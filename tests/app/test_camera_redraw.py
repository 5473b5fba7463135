"""A camera key redraws the 3D view at once, in the pose window and in the paused studio:
what the X server shows changes right after the key, with no other repaint."""

from __future__ import annotations

import numpy as np
import pytest
from PyQt6.QtCore import Qt
from PyQt6.QtGui import QGuiApplication
from PyQt6.QtTest import QTest
from PyQt6.QtWidgets import QApplication

from tests.app.gui_helpers import on_screen

pytestmark = pytest.mark.gui

PRESET = {Qt.Key.Key_1: "front", Qt.Key.Key_3: "side", Qt.Key.Key_7: "top", Qt.Key.Key_Home: "home"}


def settle(qtbot) -> None:
    for _ in range(3):
        QApplication.processEvents()
        qtbot.wait(30)


def press_and_compare(window, view, qtbot, key) -> float:
    """Fraction of the view's pixels that changed on screen after ``key``."""
    window.windowHandle().requestActivate()
    qtbot.waitUntil(lambda: QApplication.activeWindow() is window)
    view.plotter.setFocus()
    settle(qtbot)
    before = on_screen(view)
    QTest.keyClick(QApplication.focusWidget() or window, key)
    assert view.camera_preset == PRESET[key], "the key did not reach View > Camera"
    QApplication.processEvents()
    after = on_screen(view)
    return float(np.mean(np.any(before != after, axis=-1)))


@pytest.fixture
def x11():
    if QGuiApplication.platformName() != "xcb":
        pytest.skip("reads the X server's pixels of the native 3D view")


@pytest.mark.parametrize("key", [Qt.Key.Key_3, Qt.Key.Key_7, Qt.Key.Key_1])
def test_a_camera_key_redraws_the_pose_window_at_once(x11, pose_window, qtbot, key):
    w = pose_window
    w.viewport.set_camera("home", w.hips())
    w.viewport.plotter.render()
    changed = press_and_compare(w, w.viewport, qtbot, key)
    assert changed > 0.01, f"the view on screen did not change after {key.name} ({changed:.4f})"


def test_home_redraws_the_pose_window_at_once(x11, pose_window, qtbot):
    w = pose_window
    w.viewport.set_camera("top", w.hips())
    w.viewport.plotter.render()
    changed = press_and_compare(w, w.viewport, qtbot, Qt.Key.Key_Home)
    assert changed > 0.01, changed


def test_a_camera_key_redraws_the_paused_studio_at_once(x11, studio, qtbot):
    s = studio.session
    s.pause()
    qtbot.waitUntil(lambda: not s.latest.playing, timeout=5000)
    studio.viewport.set_camera("home")
    studio.viewport.plotter.render()
    changed = press_and_compare(studio, studio.viewport, qtbot, Qt.Key.Key_7)
    assert changed > 0.01, changed
