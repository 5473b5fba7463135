"""A wrist dragged onto another part of the body in the front view lands on it (real mouse
events): the view shows no depth, and the plane the hand hung in is 10-15 cm in front of the
knee."""

from __future__ import annotations

import pytest

from engine import skeleton as sk
from tests.app.gui_helpers import mouse_drag, pixel_of

J = sk.JOINT_INDEX


def test_a_hand_dragged_onto_the_opposite_knee_from_the_front_lands_on_it(pose_window):
    w = pose_window
    v = w.viewport
    p0 = w.mode.pose.positions.copy()
    mouse_drag(v, pixel_of(v, p0[0]), pixel_of(v, p0[0] - [0.0, 0.0, 0.3]), steps=8)  # a squat first
    v.set_camera("front", w.hips())
    v.plotter.render()
    p = w.mode.pose.positions.copy()
    mouse_drag(v, pixel_of(v, p[J["lwrist"]]), pixel_of(v, p[J["rknee"]]), steps=6)
    q = w.mode.pose.positions
    # the front view looks along +y: the hand is as deep as the knee (the reach then lowers
    # the body a little further, which moves the knee under the hand)
    assert abs(w.mode.targets["lwrist"].position[1] - q[J["rknee"], 1]) < 0.04
    assert abs(q[J["lwrist"], 1] - q[J["rknee"], 1]) < 0.04


@pytest.mark.parametrize("ankle, other", [("lankle", "rankle"), ("rankle", "lankle")])
def test_a_foot_stepped_forward_in_the_side_view_stays_in_its_lane(pose_window, ankle, other):
    """A short step along the floor in the side view passes over the other foot's toe,
    drawn there; landing on it would cross the feet."""
    w = pose_window
    v = w.viewport
    v.set_camera("side", w.hips())
    v.plotter.render()
    p = w.mode.pose.positions.copy()
    start = p[J[ankle]]
    mouse_drag(v, pixel_of(v, start), pixel_of(v, start + [0.0, -0.15, -0.03]), steps=8)
    target = w.mode.targets[ankle].position
    assert abs(target[0] - start[0]) < 0.04, "the foot kept its side"
    assert target[1] == pytest.approx(start[1] - 0.15, abs=0.03), "a step forward"
    q = w.mode.pose.positions
    assert abs(q[J[ankle], 0] - q[J[other], 0]) > 0.1, "the feet apart, not crossed"
