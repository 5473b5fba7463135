"""Mouse on the 3D view of the real window: Qt mouse events on the view's native widget,
under Xvfb, as a user's hand would send them."""

from __future__ import annotations

import numpy as np
import pytest

from engine import skeleton as sk
from tests.app.gui_helpers import mouse_drag, pixel_of

pytestmark = pytest.mark.gui


def paused_on_a_pose(studio, qtbot):
    studio.session.pause()
    qtbot.waitUntil(lambda: not studio.session.latest.playing, timeout=10000)
    studio.viewport.show_snapshot(studio.session.latest)
    return studio.session.latest


def test_a_plain_drag_in_empty_space_orbits_after_a_pin_was_made(studio, qtbot):
    view, s = studio.viewport, studio.session
    snap = paused_on_a_pose(studio, qtbot)
    elbow = snap.positions[sk.JOINT_INDEX["lelbow"]]
    x, y = pixel_of(view, elbow)
    mouse_drag(view, (x, y), (x + 40, y + 10), ctrl=True)
    (pin,) = s.constraints
    placed = pin.position.copy()
    qtbot.waitUntil(lambda: any(n == pin.name for n, _ in s.latest.gizmos), timeout=5000)
    view.show_snapshot(s.latest)  # the pin's gizmo is on screen now
    steps = studio.undo.history.count()
    camera = np.array(view.plotter.camera.position)
    w, h = view.plotter.width(), view.plotter.height()
    mouse_drag(view, (w - 30, h - 30), (w - 150, h - 60))  # empty sky, top right
    assert np.allclose(s.constraints[0].position, placed)
    assert studio.undo.history.count() == steps
    assert np.linalg.norm(np.array(view.plotter.camera.position) - camera) > 1e-3
    s.constraints.remove(pin.name)
    mouse_drag(view, (w - 30, h - 30), (w - 150, h - 60))
    assert list(s.constraints) == []


def test_the_look_at_target_drags_itself_not_a_pin(studio, qtbot):
    view, s, panel = studio.viewport, studio.session, studio.constraint_panel
    snap = paused_on_a_pose(studio, qtbot)
    x, y = pixel_of(view, snap.positions[sk.JOINT_INDEX["relbow"]])
    mouse_drag(view, (x, y), (x - 30, y), ctrl=True)  # a pin first, as a user would
    (pin,) = s.constraints
    panel.kinds.setCurrentText("look_at")
    panel.add_button.click()
    look = s.constraints[-1]
    qtbot.waitUntil(lambda: any(n == look.name for n, _ in s.latest.gizmos), timeout=5000)
    view.show_snapshot(s.latest)
    handle = view.gizmos.items[look.name].widget
    x, y = pixel_of(view, handle.GetCenter())
    w, h = view.plotter.width(), view.plotter.height()
    assert 0 < x < w and 0 < y < h, "the new target is in view"
    start = np.array(look.target, float)
    mouse_drag(view, (x, y), (x - 60, y + 30))
    held, moved = s.constraints
    assert np.allclose(held.position, pin.position), "the pin stays where it was"
    assert moved.name == look.name and np.linalg.norm(np.asarray(moved.target) - start) > 0.05
    camera = np.array(view.plotter.camera.position)
    mouse_drag(view, (w - 30, h - 30), (w - 150, h - 60))  # empty space afterwards: orbit
    assert np.allclose(s.constraints[1].target, moved.target)
    assert np.linalg.norm(np.array(view.plotter.camera.position) - camera) > 1e-3
