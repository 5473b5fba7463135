"""Placement of new constraints on the current pose (pure numpy, no window)."""

from __future__ import annotations

import numpy as np
import pytest

from app.constraint_placement import facing, placed_params
from engine import skeleton as sk
from engine.constraints import REGISTRY
from engine.constraints.placement import LOOK_DISTANCE
from engine.editing.catalog import constraint_catalog
from engine.gizmos import BoxGizmo, Gizmo, LineGizmo, PointGizmo
from widgets.viewport.camera import CAMERA_PRESETS, VIEW_ANGLE_DEG
from widgets.viewport.viewport import HOME_FOCUS_HEIGHT


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
    assert set(out) == {"target"} and np.allclose(out["target"], head + [LOOK_DISTANCE, 0, 0], atol=0.1)


def test_without_a_pose_or_for_other_kinds_nothing_changes():
    assert placed_params("bounds", {"joint": "root", "box_min": 0, "box_max": 0}, None) == {}
    assert placed_params("balance", {"mode": "head_over_hip"}, _pose(0)) == {}
    out = placed_params("distance", {"joint_a": "lwrist", "joint_b": "rwrist", "distance": 0.3}, _pose(0))
    pose = _pose(0)
    assert np.isclose(out["distance"], np.linalg.norm(pose[sk.JOINT_INDEX["lwrist"]] - pose[sk.JOINT_INDEX["rwrist"]]))


def _gizmo_points(g: Gizmo | None) -> list[np.ndarray]:
    if isinstance(g, PointGizmo):
        return [g.position] + ([] if g.anchor is None else [g.anchor])
    if isinstance(g, LineGizmo):
        return list(g.points)
    if isinstance(g, BoxGizmo):
        return [g.lower, g.upper]
    assert g is None, f"no points known for {type(g).__name__}"
    return []


@pytest.mark.parametrize("yaw", [0.0, 60.0, 150.0, -90.0])
@pytest.mark.parametrize("kind", sorted(constraint_catalog()))
def test_a_new_constraint_is_drawn_in_view_of_every_camera_preset(kind, yaw):
    """Placed on the pose, each kind's gizmo lies within the viewport's view cone from
    every camera preset framed on the hips (as the studio frames them): a look-at target
    1.5 m in front of the head lay 20 degrees off the home view's axis, in its corner."""
    pose = _pose(yaw)
    spec = constraint_catalog()[kind]
    defaults = {f.name: f.default for f in spec.fields}
    c = REGISTRY[kind](**{**defaults, **placed_params(kind, defaults, pose)})
    focus = np.array([pose[0, 0], pose[0, 1], HOME_FOCUS_HEIGHT])
    for preset, (offset, _up) in CAMERA_PRESETS.items():
        eye = focus + np.asarray(offset)
        axis = (focus - eye) / np.linalg.norm(focus - eye)
        for p in _gizmo_points(c.gizmo(pose)):
            ray = (np.asarray(p, float) - eye) / np.linalg.norm(np.asarray(p, float) - eye)
            angle = np.degrees(np.arccos(np.clip(ray @ axis, -1.0, 1.0)))
            assert angle < VIEW_ANGLE_DEG / 2, f"{kind}: a point {angle:.0f} deg off the {preset} view's axis"


def test_pins_added_one_after_another_go_on_different_joints():
    """Every pin added from the panel went on the left ankle (the kind's default), on top
    of the one before: a new one-joint constraint takes a joint its kind does not hold."""
    pose, defaults = _pose(0), {"joint": "lankle", "position": np.full(3, np.nan)}
    first = placed_params("pin", defaults, pose)
    assert "joint" not in first and np.allclose(first["position"], pose[sk.JOINT_INDEX["lankle"]])
    second = placed_params("pin", defaults, pose, taken={"lankle"})
    assert second["joint"] == "rankle" and np.allclose(second["position"], pose[sk.JOINT_INDEX["rankle"]])
    third = placed_params("pin", defaults, pose, taken={"lankle", "rankle"})
    assert third["joint"] not in ("lankle", "rankle")
    # the joint selected in the view wins, and its place is where that joint is
    on_elbow = placed_params("pin", defaults, pose, selected="relbow", taken={"lankle"})
    assert on_elbow["joint"] == "relbow" and np.allclose(on_elbow["position"], pose[sk.JOINT_INDEX["relbow"]])
    # without a pose the joint is still chosen; kinds on several joints are left alone
    assert placed_params("pin", defaults, None, taken={"lankle"}) == {"joint": "rankle"}
    assert "joint_a" not in placed_params("distance", {"joint_a": "lwrist", "joint_b": "rwrist"}, pose, "relbow")
