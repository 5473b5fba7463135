"""A foot joint dragged onto the other foot stops beside it (real mouse events in the
front view, where the feet are side by side across the screen): the toe dragged onto
the other foot's toe put both feet in one place."""

from __future__ import annotations

import numpy as np
import pytest

from engine import skeleton as sk
from engine.authoring.feet_apart import GAP
from tests.app.gui_helpers import mouse_drag, pixel_of

pytestmark = pytest.mark.gui
J = sk.JOINT_INDEX


def across(p: np.ndarray, ankle: str, toe: str, point: np.ndarray) -> float:
    """How far ``point`` lies to the character's left of the line from ``ankle`` to ``toe``
    of ``p``, metres, on the floor."""
    a, t = p[J[ankle]], p[J[toe]]
    along = (t - a)[:2] / np.linalg.norm((t - a)[:2])
    left = np.array([-along[1], along[0]])
    return float((point - a)[:2] @ left)


@pytest.mark.parametrize(
    "joint, onto, ankle, toe, side",
    [
        ("ltoe", "rtoe", "rankle", "rtoe", -1.0),
        ("rtoe", "ltoe", "lankle", "ltoe", 1.0),
        ("lankle", "rankle", "rankle", "rtoe", -1.0),
    ],
)
def test_a_foot_joint_dragged_onto_the_other_foot_stops_beside_it(pose_window, joint, onto, ankle, toe, side):
    w = pose_window
    v = w.viewport
    v.set_camera("front", w.hips())
    v.plotter.render()
    p = w.mode.pose.positions.copy()
    start = p[J[joint]]
    # across the screen onto the other foot's joint and 5 cm beyond it, along the floor
    end = p[J[onto]] + np.array([0.05 if side > 0 else -0.05, 0.0, start[2] - p[J[onto], 2]])
    mouse_drag(v, pixel_of(v, start), pixel_of(v, end), steps=8)
    q = w.mode.pose.positions
    target = w.mode.targets[joint].position
    # the other foot stays planted: its line is where it was; the dragged joint on its own side
    assert np.linalg.norm(q[J[ankle]] - p[J[ankle]]) < 1e-6
    assert -side * across(p, ankle, toe, target) == pytest.approx(GAP, abs=1e-6), "the target stops beside"
    assert -side * across(p, ankle, toe, q[J[joint]]) > GAP - 0.02, "the joint beside the other foot"
    gap = np.linalg.norm(q[J[joint]] - q[J[onto]])
    assert gap > 0.08, f"{joint} {100 * gap:.1f} cm from {onto}"
