"""A dragged foot joint stops beside the other foot (:func:`engine.authoring.feet_apart.kept_apart`),
passes over it and in front of it, and leaves other joints alone."""

from __future__ import annotations

import numpy as np
import pytest

from engine import skeleton as sk
from engine.authoring.feet_apart import CLEAR, GAP, kept_apart
from engine.authoring.pose_root import TOE_SHARE
from engine.kinematics.fk import fk_positions

J = sk.JOINT_INDEX


@pytest.fixture
def standing() -> np.ndarray:
    s = sk.Skeleton.canonical()
    local = np.tile([1.0, 0.0, 0.0, 0.0], (len(sk.JOINT_NAMES), 1))
    p = fk_positions(local, np.array([0.0, 0.0, 1.0]), s.offsets)
    return p - [0.0, 0.0, p[:, 2].min()]


def frame(p: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The right foot's ankle, its unit direction along the floor to its toe and the
    unit direction across it to the character's left."""
    a = p[J["rankle"]]
    along = (p[J["rtoe"]] - a) * [1.0, 1.0, 0.0]
    along /= np.linalg.norm(along)
    return a, along, np.array([-along[1], along[0], 0.0])


def test_a_toe_dragged_through_the_other_foot_stops_beside_it_on_its_side(standing):
    p = standing
    a, along, left = frame(p)
    came = p[J["ltoe"]]
    assert (came - a) @ left > GAP  # the left toe starts on the left of the right foot
    goal = p[J["rtoe"]] - 0.05 * left  # onto the right toe and beyond
    out = kept_apart("ltoe", goal, p, came)
    assert (out - a) @ left == pytest.approx(GAP)
    assert (out - a) @ along == pytest.approx((goal - a) @ along) and out[2] == pytest.approx(goal[2])


def test_a_foot_joint_over_or_in_front_of_the_other_foot_goes_where_it_is_dragged(standing):
    p = standing
    a, along, left = frame(p)
    rtoe = p[J["rtoe"]]
    over = rtoe + [0.0, 0.0, CLEAR + 0.15]
    np.testing.assert_array_equal(kept_apart("ltoe", over, p, p[J["ltoe"]]), over)
    foot = np.linalg.norm((rtoe - a)[:2]) * (1.0 + TOE_SHARE)
    ahead = a + (2.0 * foot + 0.05) * along  # a whole foot beyond the other's toe tip: a crossing step
    ahead[2] = rtoe[2]
    np.testing.assert_array_equal(kept_apart("ltoe", ahead, p, p[J["ltoe"]]), ahead)
    lane = p[J["lankle"]] + 0.1 * along  # a step forward in its own lane
    np.testing.assert_array_equal(kept_apart("lankle", lane, p, p[J["lankle"]]), lane)
    np.testing.assert_array_equal(kept_apart("lwrist", rtoe, p, p[J["lwrist"]]), rtoe)
