"""A dragged wrist or ankle stays on the mouse ray and within its limb's reach."""

from __future__ import annotations

import numpy as np
import pytest

from engine import skeleton as sk
from engine.authoring.drag_reach import REACH_SHARE, limb_reach, on_reach

ROOT = np.array([0.2, 0.0, 1.4])


def ray_through(target: np.ndarray, camera=(0.0, -4.0, 1.0)) -> tuple[np.ndarray, np.ndarray]:
    o = np.asarray(camera, float)
    return o, np.asarray(target, float) - o


def test_a_point_within_reach_stays_on_the_plane():
    p = ROOT + [0.3, -0.2, -0.1]
    assert np.array_equal(on_reach(p, *ray_through(p), ROOT, 0.55), p)


def test_a_point_beyond_reach_slides_along_the_ray_onto_the_reach():
    p = ROOT + [0.5, -0.25, 0.0]  # 56 cm away: beyond a 55 cm arm
    o, d = ray_through(p)
    q = on_reach(p, o, d, ROOT, 0.55)
    assert np.linalg.norm(q - ROOT) == pytest.approx(REACH_SHARE * 0.55, abs=1e-9)
    along = np.cross(q - o, d)
    assert np.linalg.norm(along) < 1e-9, "still on the mouse ray: the same pixel"
    assert q[1] > p[1], "it gave up depth towards the shoulder's plane"


def test_a_ray_beyond_reach_gives_the_point_the_straight_limb_points_at():
    p = ROOT + [0.7, -0.2, 0.0]
    o, d = ray_through(p)
    q = on_reach(p, o, d, ROOT, 0.55)
    assert abs(float((q - ROOT) @ d)) < 1e-9, "the ray's point nearest the root"


def test_only_wrists_and_ankles_end_a_limb():
    pos = sk.Skeleton.canonical().rest_positions()
    root, length = limb_reach(pos, "lwrist")
    assert np.allclose(root, pos[sk.JOINT_INDEX["lshoulder"]]) and 0.4 < length < 0.7
    assert limb_reach(pos, "rankle") is not None
    assert limb_reach(pos, "lelbow") is None and limb_reach(pos, "root") is None
