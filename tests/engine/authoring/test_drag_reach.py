"""A dragged wrist or ankle stays on the mouse ray, and the depth it takes follows its
limb's stretch: kept near the press, the root's plane at full stretch, within reach."""

from __future__ import annotations

import numpy as np
import pytest

from engine import skeleton as sk
from engine.authoring.drag_reach import limb_reach, on_reach, stretched_depth

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


def test_a_small_drag_keeps_the_depth_of_the_press():
    q = drag_to(HANGING + [-0.05, 0.0, 0.03])  # towards the body, up a little
    assert q[1] == pytest.approx(HANGING[1], abs=1e-9)


def test_a_limb_stretched_on_screen_lies_in_its_roots_plane():
    """The T-pose in the front view: the wrist dragged to where a straight arm out to
    the side would be on screen ends there, at the shoulder's depth (not 21 cm forward)."""
    t_pose = ROOT + [ARM, 0.0, 0.0]
    q = drag_to(t_pose)
    assert np.linalg.norm(q - t_pose) < 1e-6
    ray = t_pose - CAMERA
    assert np.linalg.norm(np.cross(q - CAMERA, ray)) < 1e-9, "still under the mouse"


def test_the_point_stays_within_reach_on_the_way_and_the_way_back():
    out, back = [], []
    for s in np.linspace(0.0, 1.0, 21):
        screen = HANGING + s * (ROOT + [ARM, 0.0, 0.0] - HANGING)
        out.append(drag_to(screen))
    for s in np.linspace(1.0, 0.0, 21):
        back.append(drag_to(HANGING + s * (ROOT + [ARM, 0.0, 0.0] - HANGING)))
    assert max(np.linalg.norm(p - ROOT) for p in out) <= ARM + 1e-9
    np.testing.assert_allclose(out, back[::-1], atol=1e-12)  # the mouse position alone decides
    depths = [p[1] for p in out]
    assert all(b >= a - 1e-12 for a, b in zip(depths, depths[1:])), "the depth moves one way, towards the shoulder"


def test_the_depth_rule():
    assert stretched_depth(0.2, 0.3, -0.2, 0.5) == -0.2
    assert stretched_depth(0.4, 0.3, -0.2, 0.5) == pytest.approx(-0.1)
    assert stretched_depth(0.7, 0.3, -0.2, 0.5) == 0.0
    assert stretched_depth(0.7, 0.6, -0.2, 0.5) == -0.2, "a press beyond reach keeps its depth"


def test_only_wrists_and_ankles_end_a_limb():
    pos = sk.Skeleton.canonical().rest_positions()
    root, length = limb_reach(pos, "lwrist")
    assert np.allclose(root, pos[sk.JOINT_INDEX["lshoulder"]]) and 0.4 < length < 0.7
    assert limb_reach(pos, "rankle") is not None
    assert limb_reach(pos, "lelbow") is None and limb_reach(pos, "root") is None
