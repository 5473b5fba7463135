"""Real presses on the hips in the side view of the pose window, where the two hip joints
are drawn on top of each other just below the pelvis, where the legs start: a press on
either hip joint takes the pelvis (a squat, the body raised), never a target on the hip
joint, which folds the legs under the body."""

from __future__ import annotations

import numpy as np
import pytest

from engine import skeleton as sk
from tests.app.gui_helpers import mouse_drag, pixel_of

pytestmark = pytest.mark.gui

J = sk.JOINT_INDEX
ANKLES = [J["lankle"], J["rankle"]]


def _side_view(w) -> None:
    w.viewport.set_camera("side", w.hips())
    w.viewport.plotter.render()


@pytest.mark.parametrize("hip", ["lhip", "rhip"])
def test_a_press_on_a_hip_joint_in_the_side_view_squats_the_body(pose_window, hip):
    w = pose_window
    view = w.viewport
    _side_view(w)
    before = w.mode.pose.positions.copy()
    start = pixel_of(view, before[J[hip]])
    end = pixel_of(view, before[J[hip]] - [0.0, 0.0, 0.20])
    mouse_drag(view, start, end, steps=6)
    assert set(w.mode.targets) == {"root"}, "the pelvis was dragged, not the hip joint"
    assert w.selected == "root"
    after = w.mode.pose.positions
    assert before[0, 2] - after[0, 2] == pytest.approx(0.20, abs=0.03)
    assert np.abs(after[ANKLES] - before[ANKLES]).max() < 0.01, "the feet stay planted"
    assert after[[J["lknee"], J["rknee"]], 2].min() > 0.3, "the knees bend, not fold to the floor"


def test_a_hip_joint_dragged_up_after_a_low_reach_stands_the_body_up(pose_window):
    """A wrist brought to the opposite shin (below what the stooping trunk reaches)
    crouches; the hips are then dragged back up in the side view, from a press on a hip
    joint."""
    w = pose_window
    view = w.viewport
    standing = w.mode.pose.positions[0, 2]
    knee = w.mode.pose.positions[J["lknee"]].copy()
    w.drag_joint("rwrist", knee + [0.0, -0.08, -0.20])
    crouched = w.mode.pose.positions.copy()
    assert standing - crouched[0, 2] > 0.05, "the low reach crouched the body"
    _side_view(w)
    start = pixel_of(view, crouched[J["rhip"]])
    end = pixel_of(view, crouched[J["rhip"]] + [0.0, 0.0, standing - crouched[0, 2] + 0.05])
    mouse_drag(view, start, end, steps=8)
    assert set(w.mode.targets) == {"rwrist", "root"}
    assert w.mode.pose.positions[0, 2] == pytest.approx(standing, abs=0.02), "standing again"
