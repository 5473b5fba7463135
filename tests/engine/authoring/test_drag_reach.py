"""A dragged wrist or ankle stays on the mouse ray, and its depth follows the drag's
length: nearly kept for a small move, the root's plane after a long one, within reach."""

from __future__ import annotations

import numpy as np
import pytest

from engine import skeleton as sk
from engine.authoring.drag_reach import dragged_depth, limb_reach, on_reach, onto_body

ROOT = np.array([0.2, 0.0, 1.4])  # a shoulder
ARM = 0.51
CAMERA = np.array([0.0, -4.0, 1.4])  # the front view: looking along +Y
NORMAL = np.array([0.0, 1.0, 0.0])
HANGING = ROOT + [0.19, -0.21, -0.31]  # the mean pose's wrist: 21 cm in front of the shoulder


def drag_to(screen_point: np.ndarray) -> np.ndarray:
    """Where the wrist pressed at HANGING goes with the mouse over ``screen_point``."""
    direction = screen_point - CAMERA
    t = float((HANGING - CAMERA) @ NORMAL) / float(direction @ NORMAL)
    return on_reach(CAMERA + t * direction, HANGING, CAMERA, direction, NORMAL, ROOT, ARM)


def test_a_small_drag_nearly_keeps_the_depth_of_the_press():
    q = drag_to(HANGING + [-0.05, 0.0, 0.03])  # towards the body, up a little: 6 cm
    assert q[1] == pytest.approx(HANGING[1], abs=0.04)
    assert drag_to(HANGING)[1] == pytest.approx(HANGING[1], abs=1e-9)


@pytest.mark.parametrize("share", [1.0, 0.9, 0.8])
def test_a_wrist_dragged_out_to_the_side_lies_in_the_shoulders_plane(share):
    """The T-pose in the front view: the wrist dragged to where an arm out to the side
    would be on screen ends there, near the shoulder's depth (not 21 cm forward), even
    when the drag stops short of the straight arm (the elbow bent towards the camera
    looks straight from the front)."""
    t_pose = ROOT + [share * ARM, 0.0, 0.0]
    q = drag_to(t_pose)
    assert abs(q[1] - ROOT[1]) < 0.01
    out = q - ROOT
    assert np.degrees(np.arctan2(-out[1], out[0])) < 5.0
    assert np.linalg.norm(np.cross(q - CAMERA, t_pose - CAMERA)) < 1e-9, "still under the mouse"


def test_the_point_stays_within_reach_and_the_mouse_alone_decides():
    goal = ROOT + [ARM, 0.0, 0.0]
    out = [drag_to(HANGING + s * (goal - HANGING)) for s in np.linspace(0.0, 1.0, 21)]
    back = [drag_to(HANGING + s * (goal - HANGING)) for s in np.linspace(1.0, 0.0, 21)]
    assert max(np.linalg.norm(p - ROOT) for p in out) <= ARM + 1e-6
    np.testing.assert_allclose(out, back[::-1], atol=1e-12)
    depths = [p[1] for p in out]
    assert all(b >= a - 1e-9 for a, b in zip(depths, depths[1:])), "the depth moves one way, towards the shoulder"


def test_the_depth_rule():
    assert dragged_depth(0.0, 0.3, -0.2, 0.5) == -0.2
    assert dragged_depth(0.1875, 0.3, -0.2, 0.5) == pytest.approx(-0.1)
    assert dragged_depth(0.6, 0.3, -0.2, 0.5) == 0.0
    assert dragged_depth(0.1, 0.48, -0.2, 0.5) == pytest.approx(-np.sqrt(0.5**2 - 0.48**2)), "cut to the reach"
    assert dragged_depth(0.0, 0.48, -0.2, 0.5, within=False) == -0.2, "a press beyond reach keeps its depth"


def test_only_wrists_and_ankles_end_a_limb():
    pos = sk.Skeleton.canonical().rest_positions()
    root, length = limb_reach(pos, "lwrist")
    assert np.allclose(root, pos[sk.JOINT_INDEX["lshoulder"]]) and 0.4 < length < 0.7
    assert limb_reach(pos, "rankle") is not None
    assert limb_reach(pos, "lelbow") is None and limb_reach(pos, "root") is None


def test_a_wrist_whose_mouse_ray_passes_a_joint_of_the_body_takes_its_depth():
    p = sk.Skeleton.canonical().rest_positions()
    knee = p[sk.JOINT_INDEX["rknee"]]
    ray = np.array([0.0, 1.0, 0.0])  # the front view looks along +y
    near = knee + [0.03, -0.25, 0.01]  # under the cursor 3 cm beside the knee, 25 cm in front of it
    on = onto_body(near, ray, p, "lwrist")
    assert np.allclose(on, knee + [0.03, 0.0, 0.01])  # same ray, the knee's depth
    assert onto_body(knee + [0.10, -0.25, 0.0], ray, p, "lwrist") is None  # passes 10 cm from every joint
    elbow = p[sk.JOINT_INDEX["lelbow"]]
    assert onto_body(elbow + [0.0, -0.25, 0.0], ray, p, "lwrist") is None  # the dragged arm's own joints
    assert onto_body(knee + [0.0, -0.25, 0.0], ray, p, "upperneck") is None  # only wrists and ankles


def test_an_ankle_lands_on_no_foot_but_on_the_other_knee():
    """Seen from the side (rays along -x) the feet are drawn over each other: a foot moved
    across the other's toe or ankle keeps its own depth; the other knee (a foot on a knee,
    as in the tree pose) is still a touch."""
    p = sk.Skeleton.canonical().rest_positions()
    ray = np.array([-1.0, 0.0, 0.0])
    for foot in ("rtoe", "rankle", "ltoe"):
        over = p[sk.JOINT_INDEX[foot]] + [0.3, 0.0, 0.01]
        assert onto_body(over, ray, p, "lankle") is None, foot
    knee = p[sk.JOINT_INDEX["rknee"]]
    assert np.allclose(onto_body(knee + [0.3, 0.0, 0.01], ray, p, "lankle"), knee + [0.0, 0.0, 0.01])
    assert onto_body(p[sk.JOINT_INDEX["rtoe"]] + [0.3, 0.0, 0.01], ray, p, "lwrist") is not None, "a hand still does"
