"""Pose mode driven programmatically: dragging targets, rotations, constraints, clip frames."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from engine import skeleton as sk
from engine.authoring.pose_mode import PoseMode, PoseOptions
from engine.constraints import LookAtConstraint
from engine.errors import UserError
from engine.kinematics import quat_np as QN
from engine.kinematics.fk import fk

J = sk.JOINT_INDEX

LW, RW = sk.JOINT_INDEX["lwrist"], sk.JOINT_INDEX["rwrist"]
FEET = [sk.JOINT_INDEX[j] for j in ("lankle", "rankle", "ltoe", "rtoe")]


def bones(positions: np.ndarray) -> np.ndarray:
    return np.linalg.norm(positions[1:] - positions[list(sk.PARENTS[1:])], axis=-1)


def drag(pm: PoseMode, joint: str, by, events: int = 30):
    start = pm.pose.positions[sk.JOINT_INDEX[joint]].copy()
    for k in range(1, events + 1):
        pm.set_target(joint, start + np.asarray(by, float) * k / events)
        pm.solve()
    return start + np.asarray(by, float)


def test_dragging_a_wrist_30_cm_keeps_it_on_target_bones_fixed_feet_on_the_floor(vae):
    pm = PoseMode(vae, height=1.75)
    assert pm.character.height == pytest.approx(1.75)
    rest_bones = bones(pm.pose.positions)
    target = drag(pm, "lwrist", [0.0, -0.3, 0.0])
    p = pm.pose
    assert np.linalg.norm(p.positions[LW] - target) < 0.01
    assert np.abs(bones(p.positions) - rest_bones).max() < 1e-6
    assert np.allclose(rest_bones, np.linalg.norm(pm.character.skeleton.offsets[1:], axis=-1), atol=1e-9)
    assert p.positions[FEET, 2].min() >= 0.0 and p.positions[:, 2].min() >= 0.0
    assert np.linalg.norm(p.decoded[LW] - target) < 0.03  # the latent itself follows, not only the limb step


@pytest.mark.parametrize("by", [[0.3, 0.0, 0.0], [0.0, 0.0, -0.3], [0.0, 0.0, 0.3]])
def test_after_the_drag_the_settled_pose_meets_the_target_in_every_direction(vae, by):
    pm = PoseMode(vae, height=1.75)
    rest_bones = bones(pm.pose.positions)
    target = drag(pm, "lwrist", by, events=10)
    p = pm.settle()
    assert np.linalg.norm(p.positions[LW] - target) < 0.01
    assert np.abs(bones(p.positions) - rest_bones).max() < 1e-6 and p.positions[:, 2].min() >= 0.0


def test_a_rotation_target_turns_the_hand_and_weight_zero_or_disabled_releases_it(vae):
    pm = PoseMode(vae)
    q = QN.mul(np.array([np.cos(0.4), np.sin(0.4), 0.0, 0.0]), pm.pose.local_rot[0])
    pm.set_target("lwrist", rotation=q)
    pm.solve()
    world = fk(pm.pose.local_rot, pm.pose.root_pos, pm.character.skeleton.offsets)[1][LW]
    assert abs(float(world @ q)) == pytest.approx(1.0, abs=1e-9)
    held = pm.pose.positions[LW].copy()
    pm.set_target("lwrist", position=held + [0, 0, 0.2], weight=0.0)
    pm.solve()
    assert pm.pose.positions[LW, 2] < held[2] + 0.05  # a zero weight does not pull it up 20 cm
    pm.clear_rotation("lwrist")
    assert pm.targets["lwrist"].rotation is None
    pm.clear_targets()
    assert pm.targets == {}


def test_other_constraint_kinds_act_in_pose_mode(vae):
    pm = PoseMode(vae)
    look = LookAtConstraint(name="look", joint="upperneck", target=np.array([3.0, 0.0, 1.6]), weight=5.0)
    pm.constraints.append(look)
    for _ in range(5):
        pm.solve()
    pm.settle()
    head = fk(pm.pose.local_rot, pm.pose.root_pos, pm.character.skeleton.offsets)[1][sk.JOINT_INDEX["upperneck"]]
    forward = QN.rotate(head, look.axis)
    to_target = look.target - pm.pose.positions[sk.JOINT_INDEX["upperneck"]]
    cos = forward @ to_target / np.linalg.norm(to_target) / np.linalg.norm(forward)
    assert cos > 0.5  # the head turned towards +X from facing -Y (cos 0 at the start)


@pytest.fixture(scope="module")
def example_clip():
    from engine.motion.retarget import load_motion

    return load_motion(Path(__file__).resolve().parents[3] / "assets" / "clips" / "example.bvh")


def test_a_clip_frame_starts_the_pose_where_the_clip_stands(vae, example_clip):
    pm = PoseMode.from_clip_frame(vae, example_clip, 10)
    assert np.allclose(pm.pose.root_pos[:2], example_clip.root_pos[10, :2], atol=1e-6)
    clip = example_clip.positions()[10]
    rel = lambda p: p - p[0]  # noqa: E731
    mean = PoseMode(vae).pose.positions
    err = lambda p: np.linalg.norm(rel(p) - rel(clip), axis=-1).mean()  # noqa: E731
    assert err(pm.pose.positions) < 0.7 * err(mean)  # the encoded pose, not the mean
    with pytest.raises(UserError, match="frame 1000000"):
        PoseMode.from_clip_frame(vae, example_clip, 10**6)


def _drag(mode, joint, goal, events=20):
    start = mode.pose.positions[J[joint]].copy()
    for t in np.linspace(0.0, 1.0, events + 1)[1:]:
        mode.set_target(joint, position=start + t * (np.asarray(goal) - start))
        mode.solve()


def test_planted_feet_stay_and_the_body_keeps_its_weight_over_them(vae):
    """A hand dragged to the opposite knee: with the defaults the feet do not slide and the
    centre of mass stays inside the feet's support polygon (the benchmark's measure);
    without planting, balance, crouch and stoop (a bare latent solve) the feet slide and
    the weight leaves the feet."""
    from engine.authoring.pose_metrics import check_pose
    from engine.authoring.pose_mode import PoseMode, PoseOptions

    def run(options):
        mode = PoseMode(vae, options=options)
        feet = mode.pose.positions[[J["lankle"], J["rankle"]], :2].copy()
        goal = mode.pose.positions[J["lknee"]] + [0.0, -0.08, 0.0]
        _drag(mode, "rwrist", goal)
        slide = np.linalg.norm(mode.pose.positions[[J["lankle"], J["rankle"]], :2] - feet, axis=-1).max()
        check = check_pose(mode.pose.local_rot, mode.pose.root_pos, mode.character.skeleton.offsets)
        return slide, check.balance_margin_cm, np.linalg.norm(mode.pose.positions[J["rwrist"]] - goal)

    slide, margin, err = run(PoseOptions())
    assert slide < 0.01 and margin is not None and margin > 2.0 and err < 0.06
    bare = PoseOptions(plant_feet=False, balance=False, crouch_share=0.0, stoop_deg=0.0)
    slide_before, margin_before, _ = run(bare)
    assert slide_before > 0.2 and margin_before is not None and margin_before < -10.0


def test_dragging_the_pelvis_down_squats_on_planted_feet(vae):
    """The pelvis goes where it is dragged (40 cm down) and the planted legs bend under it;
    before, the root was held where it stood and the drag did nothing."""
    from engine.authoring.pose_mode import PoseMode, PoseOptions

    mode = PoseMode(vae)
    feet = mode.pose.positions[[J["lankle"], J["rankle"]]].copy()
    goal = mode.pose.root_pos + [0.0, 0.0, -0.4]
    _drag(mode, "root", goal)
    assert abs(mode.pose.root_pos[2] - goal[2]) < 0.02  # level, the pelvis balances over the feet
    assert np.abs(mode.pose.positions[[J["lankle"], J["rankle"]]] - feet).max() < 0.01
    held = PoseMode(vae, options=PoseOptions(plant_feet=False, balance=False))
    _drag(held, "root", goal)
    assert np.linalg.norm(held.pose.root_pos - goal) > 0.3


def test_a_dragged_foot_is_planted_where_it_is_left(vae):
    from engine.authoring.pose_mode import PoseMode

    mode = PoseMode(vae)
    goal = mode.pose.positions[J["lankle"]] + [0.0, -0.25, 0.0]
    _drag(mode, "lankle", goal)
    mode.remove_target("lankle")
    mode.solve()
    assert np.linalg.norm(mode.planted["lankle"][:2] - goal[:2]) < 0.03
    assert np.linalg.norm(mode.pose.positions[J["lankle"], :2] - goal[:2]) < 0.03


def test_a_wrist_dragged_beyond_the_arm_takes_further_rounds_and_one_within_reach_does_not(vae):
    """A drag event whose wrist target lies out of the arm's reach solves further rounds
    (more latent steps, the body bends further) until it is within ``reach_tolerance``; a
    target within reach costs one round, as with ``reach_rounds=0``."""
    far = PoseMode(vae)
    near = PoseMode(vae)
    w = far.pose.positions[sk.JOINT_INDEX["rwrist"]].copy()
    far.set_target("rwrist", w + np.array([0.0, -0.25, -0.45]))
    near.set_target("rwrist", w + np.array([0.0, -0.05, 0.0]))
    rounds = {}
    for name, pm in (("far", far), ("near", near)):
        solve = pm.character.solve

        def counted(*a, _name=name, _solve=solve, **k):
            rounds[_name] = rounds.get(_name, 0) + 1
            return _solve(*a, **k)

        pm.character.solve = counted
        pm.solve()
    assert 1 < rounds["far"] <= 1 + PoseOptions().reach_rounds and rounds["near"] == 1
    one = PoseMode(vae, options=PoseOptions(reach_rounds=0))
    one.set_target("rwrist", far.targets["rwrist"].position)
    one.solve()
    assert far.shortfall() < one.shortfall() - 0.01
    assert near.shortfall() < 1e-6
    same = PoseMode(vae, options=PoseOptions(reach_rounds=0))
    same.set_target("rwrist", near.targets["rwrist"].position)
    same.solve()
    np.testing.assert_allclose(same.pose.positions, near.pose.positions, atol=1e-6)
