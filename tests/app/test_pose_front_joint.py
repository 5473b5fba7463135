"""A real press where two joints are drawn on top of each other (the side view of the
pose window: the elbows 1 pixel apart, the knees 5) grabs the one drawn in front, the
one the user sees, not whichever centre happens to be a pixel nearer (a press on the
near ankle must not drag the far one)."""

from __future__ import annotations

import numpy as np
import pytest

from engine import skeleton as sk
from tests.app.gui_helpers import mouse_drag, pixel_of

pytestmark = pytest.mark.gui

J = sk.JOINT_INDEX


@pytest.mark.parametrize("pair", [("lelbow", "relbow"), ("lknee", "rknee")])
def test_a_press_on_two_overlapping_joints_grabs_the_front_one(pose_window, pair):
    w = pose_window
    view = w.viewport
    view.set_camera("side", w.hips())
    view.plotter.render()
    positions = w.mode.pose.positions
    camera = np.asarray(view.plotter.camera.position, float)
    near, far = sorted(pair, key=lambda j: np.linalg.norm(positions[J[j]] - camera))
    start = pixel_of(view, positions[J[far]])
    assert np.hypot(*np.subtract(start, pixel_of(view, positions[J[near]]))) < 6.0, "drawn over each other"
    mouse_drag(view, start, (start[0] - 30, start[1]), steps=4)
    assert set(w.mode.targets) == {near}
    assert w.selected == near
