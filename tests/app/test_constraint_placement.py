"""Placement of new constraints on the current pose (pure numpy, no window)."""

from __future__ import annotations

import numpy as np

from app.constraint_placement import facing, placed_params
from engine import skeleton as sk


def _pose(yaw_deg: float, at=(3.0, -5.0, 0.0)) -> np.ndarray:
    rest = sk.Skeleton.canonical().rest_positions() + [0, 0, 0.95]
    a = np.radians(yaw_deg)
    rz = np.array([[np.cos(a), -np.sin(a), 0], [np.sin(a), np.cos(a), 0], [0, 0, 1]])
    return rest @ rz.T + at


def test_facing_follows_the_hips():
    assert np.allclose(facing(_pose(0)), [0, -1, 0], atol=0.05)  # rest: faces -Y
    assert np.allclose(facing(_pose(90)), [1, 0, 0], atol=0.05)  # turned left by 90 degrees


def test_look_at_target_is_in_front_of_the_head_wherever_the_body_is():
    pose = _pose(90)
    defaults = {"joint": "upperneck", "target": np.array([0.0, -2.0, 1.6]), "axis": np.array([0, -1.0, 0])}
    out = placed_params("look_at", defaults, pose)
    head = pose[sk.JOINT_INDEX["upperneck"]]
    assert set(out) == {"target"} and np.allclose(out["target"], head + [1.5, 0, 0], atol=0.1)


def test_without_a_pose_or_for_other_kinds_nothing_changes():
    assert placed_params("bounds", {"joint": "root", "box_min": 0, "box_max": 0}, None) == {}
    assert placed_params("balance", {"mode": "head_over_hip"}, _pose(0)) == {}
    out = placed_params("distance", {"joint_a": "lwrist", "joint_b": "rwrist", "distance": 0.3}, _pose(0))
    pose = _pose(0)
    assert np.isclose(out["distance"], np.linalg.norm(pose[sk.JOINT_INDEX["lwrist"]] - pose[sk.JOINT_INDEX["rwrist"]]))
