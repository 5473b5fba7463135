"""The gizmo of a constraint limited to a frame range is drawn only on the frames where
it acts (its range and blends), in the pose window and in the paused studio: a pin for
frames 20-40 is not seen holding its joint on frame 10 or 50. The range is set in the
constraint editors with real clicks and typed numbers, the frame with a real click on
the window's timeline, and what is drawn is read from the X server's pixels."""

from __future__ import annotations

import numpy as np
import pytest
from PyQt6.QtCore import Qt
from PyQt6.QtGui import QGuiApplication
from PyQt6.QtTest import QTest
from PyQt6.QtWidgets import QApplication, QTabWidget

from tests.app.gui_helpers import add_wrist_pin, ctrl_drag_pin, on_screen, scrub, type_number

pytestmark = pytest.mark.gui


@pytest.fixture
def x11():
    if QGuiApplication.platformName() != "xcb":
        pytest.skip("reads the X server's pixels of the native 3D view")


def gizmo_pixels(view) -> int:
    """How many pixels of the 3D view on screen have the gizmos' cyan."""
    view.plotter.render()
    img = on_screen(view).astype(int)
    return int(np.sum((img[..., 0] < 80) & (img[..., 1] > 170) & (img[..., 2] > 200)))


def limit(rng, start: int, end: int) -> None:
    """Tick the editor's *only frames* and type ``start`` and ``end``."""
    QTest.mouseClick(rng.limited, Qt.MouseButton.LeftButton, pos=rng.limited.rect().center())
    type_number(rng.end, end)
    type_number(rng.start, start)


def test_the_pose_window_draws_a_range_limited_pin_only_on_its_frames(x11, pose_window):
    w = pose_window
    view = w.viewport
    view.set_camera("front", w.hips())
    pin = add_wrist_pin(w)
    assert pin.name in view.gizmos.items and gizmo_pixels(view) > 10, "a pin on every frame shows at frame 0"
    limit(w.constraints.panel.editor.range, 20, 40)
    assert w.mode.constraints[0].frames == (20, 40) and w.frame == 0
    assert pin.name not in view.gizmos.items and gizmo_pixels(view) == 0, "frame 0 is outside 20-40"
    scrub(w, 30)
    assert w.frame == 30
    assert pin.name in view.gizmos.items and gizmo_pixels(view) > 10
    scrub(w, 50)
    assert w.frame == 50
    assert pin.name not in view.gizmos.items and gizmo_pixels(view) == 0


def test_the_paused_studio_draws_a_range_limited_pin_only_on_its_frames(x11, studio, qtbot):
    view, s, panel = studio.viewport, studio.session, studio.constraint_panel
    name = ctrl_drag_pin(studio, qtbot).name
    qtbot.waitUntil(lambda: name in view.gizmos.items, timeout=5000)
    assert gizmo_pixels(view) > 10
    tabs = panel.parentWidget()
    while not isinstance(tabs, QTabWidget):
        tabs = tabs.parentWidget()
    tabs.setCurrentWidget(panel)
    qtbot.waitUntil(lambda: panel.editor is not None and panel.editor.range is not None)
    limit(panel.editor.range, 60, 80)
    assert s.constraints[0].frames == (60, 80)
    qtbot.waitUntil(lambda: name not in view.gizmos.items, timeout=5000)
    assert gizmo_pixels(view) == 0, "frame 50 is outside 60-80"
    slider = studio.timeline.slider
    QTest.mouseClick(slider, Qt.MouseButton.LeftButton, pos=slider.point_of(70))
    QApplication.processEvents()
    qtbot.waitUntil(lambda: s.latest.frame == slider.value() and name in view.gizmos.items, timeout=10000)
    assert 66 <= slider.value() <= 74 and not s.latest.playing
    assert gizmo_pixels(view) > 10
