"""The head onto its tracker by the spine after the solve (engine.solver.limb_ik.reach_head_local,
setting ``head_reach``)."""

from __future__ import annotations

import numpy as np
import pytest
import torch

from engine import skeleton as sk
from engine.constraints import PinConstraint
from engine.kinematics import quaternion as Q
from engine.kinematics.fk import fk
from engine.methods.dragposer import DragPoserMethod
from engine.motion.clip import Motion
from engine.solver import limb_ik
from engine.tracking import simulate
from tests.engine.test_optimizer_standins import CountingPredictor, MLPDecoder

J = sk.JOINT_INDEX
HEAD, BASE = J["upperneck"], J["lowerback"]
SPINE = {J[n] for n in ("lowerback", "upperback", "chest", "lowerneck")}


def _pose(seed: int):
    rng = np.random.default_rng(seed)
    local = Q.normalize(np.array([1.0, 0, 0, 0]) + rng.normal(0, 0.15, size=(sk.NUM_JOINTS, 4)))
    return local, np.array([0.1, -0.2, 0.95]), sk.Skeleton.canonical().offsets, rng


def _swung_target(local, root, off, rng, degrees):
    """The head's position turned about the lower back by ``degrees`` (the chord's length kept)."""
    pos, _ = fk(local, root, off)
    axis = rng.normal(size=3)
    turn = Q.from_axis_angle(axis / np.linalg.norm(axis), np.radians(degrees))
    return pos[BASE] + Q.rotate(turn, pos[HEAD] - pos[BASE]), pos


@pytest.mark.parametrize("seed", range(5))
def test_the_spine_brings_the_head_onto_a_target_and_moves_nothing_below_it(seed):
    local, root, off, rng = _pose(seed)
    target, before = _swung_target(local, root, off, rng, rng.uniform(5, 25))
    got = limb_ik.reach_head_local(local, root, off, target)
    pos, _ = fk(got, root, off)
    have, want = pos[HEAD] - pos[BASE], target - pos[BASE]
    cos = have @ want / np.linalg.norm(have) / np.linalg.norm(want)
    assert np.degrees(np.arccos(min(cos, 1.0))) < 0.1, "the chord points at the target"
    # the bend changes the chord's length a little: what is left is a fraction of the swing
    assert np.linalg.norm(pos[HEAD] - target) < 0.3 * np.linalg.norm(before[HEAD] - target)
    changed = {j for j in range(sk.NUM_JOINTS) if not np.allclose(np.abs(got[j] @ local[j]), 1.0, atol=1e-12)}
    assert changed == SPINE, "only the spine turns; arms and head keep their local rotations"
    np.testing.assert_allclose(pos[: BASE + 1], before[: BASE + 1], atol=1e-12, err_msg="hips and legs stay")
    # each spine joint takes a share of the swing: none is left straight while another takes it all
    angles = [np.degrees(Q.angle(got[j], local[j])) for j in sorted(SPINE)]
    assert max(angles) < 3 * min(angles)


def test_a_target_beyond_the_chord_is_met_in_direction_only():
    local, root, off, rng = _pose(7)
    target, before = _swung_target(local, root, off, rng, 15.0)
    far = before[BASE] + 1.2 * (target - before[BASE])
    pos, _ = fk(limb_ik.reach_head_local(local, root, off, far), root, off)
    have, want = pos[HEAD] - pos[BASE], far - pos[BASE]
    assert np.degrees(np.arccos(min(have @ want / np.linalg.norm(have) / np.linalg.norm(want), 1.0))) < 0.1
    assert np.linalg.norm(pos[HEAD] - far) > 0.1, "the spine does not stretch to a target beyond the chord"


def test_finish_reaches_the_head_first_and_the_wrist_after_it():
    local, root, off, rng = _pose(3)
    target, before = _swung_target(local, root, off, rng, 20.0)
    # well within the arm's reach wherever the chest's turn takes the shoulder
    wrist = before[J["lshoulder"]] + 0.6 * (before[J["lwrist"]] - before[J["lshoulder"]])
    got, pos = limb_ik.finish(local, root, off, {HEAD: target, J["lwrist"]: wrist}, {})
    _, head_only = limb_ik.finish(local, root, off, {HEAD: target}, {})
    np.testing.assert_allclose(pos[HEAD], head_only[HEAD], atol=1e-12, err_msg="the arm's reach moves no head")
    assert np.linalg.norm(pos[HEAD] - target) < 0.3 * np.linalg.norm(before[HEAD] - target)
    assert np.linalg.norm(pos[J["lwrist"]] - wrist) < 1e-6, "the arm reaches from where the chest put it"
    _, alone = limb_ik.finish(local, root, off, {J["lwrist"]: wrist}, {})
    np.testing.assert_allclose(alone[HEAD], before[HEAD], atol=1e-12, err_msg="no head target: the spine stays")


@pytest.fixture
def clip() -> Motion:
    f = 12
    t = np.arange(f) / 60.0
    rng = np.random.default_rng(0)
    rot = Q.normalize(np.array([1.0, 0, 0, 0]) + rng.normal(0, 0.08, size=(f, 22, 4)))
    return Motion(rot, np.stack([0.2 * t, -0.8 * t, 1.0 + 0 * t], -1))


def _run(clip, **kw):
    torch.manual_seed(0)
    m = DragPoserMethod(MLPDecoder(), CountingPredictor(), iterations=3, max_iterations=20, **kw)
    tr = simulate(clip, "4")
    m.reset(clip.skeleton)
    out = [m.step(tr.frame(i)) for i in range(len(clip))]
    head = tr.positions[:, tr.joints.index("upperneck")]
    chords = np.array([r.positions[HEAD] - r.positions[BASE] for r in out])
    wanted = head - np.array([r.positions[BASE] for r in out])
    cos = (chords * wanted).sum(-1) / np.linalg.norm(chords, axis=-1) / np.linalg.norm(wanted, axis=-1)
    return np.degrees(np.arccos(np.clip(cos, -1, 1))), np.linalg.norm(
        np.array([r.positions[HEAD] for r in out]) - head, axis=-1
    )


def test_with_a_hip_tracker_the_head_points_at_its_tracker_and_a_held_upper_body_is_left_alone(clip):
    on_angle, on_err = _run(clip)
    off_angle, off_err = _run(clip, head_reach=False)
    assert on_angle.max() < 0.2 and off_angle.min() > 1.0
    assert on_err.mean() < 0.5 * off_err.mean()
    tr = simulate(clip, "4")
    # the spine's turn carries the arms: a pinned elbow would leave the pin the solve met
    for joint, reached in (("chest", False), ("lelbow", False), ("rwrist", False), ("lknee", True)):
        m = DragPoserMethod(MLPDecoder(), CountingPredictor(), iterations=3, max_iterations=20)
        m.add_constraint(PinConstraint(name="pin", joint=joint))
        m.reset(clip.skeleton)
        m.step(tr.frame(0))
        assert (HEAD in m.plan(tr.frame(1)).reach) is reached, f"a user's constraint on {joint}"


@pytest.mark.parametrize(
    ("preset", "expected"),
    [("4", True), ("3-hip-hands", True), ("6x3dof", True), ("6", True), ("3-head-hands", False), ("5", False)],
)
def test_every_profile_with_a_hip_tracker_reaches_the_head_by_the_spine(preset, expected):
    from engine.solver import OptimizerSettings
    from engine.solver.profiles import effective
    from engine.tracking.presets import PRESET_SENSORS

    joints = [s.joint for s in PRESET_SENSORS[preset]]
    hip = all(s.dof == 6 for s in PRESET_SENSORS[preset] if s.joint == "root")
    assert effective(OptimizerSettings(), joints, explicit=(), hip_rotation=hip).head_reach is expected
    assert (
        effective(
            OptimizerSettings(head_reach=not expected), joints, explicit=("head_reach",), hip_rotation=hip
        ).head_reach
        is not expected
    )


def test_the_reach_is_as_smooth_as_its_input_however_many_passes(monkeypatch):
    """A rounding difference in the decoded pose (1e-7) stays that small in the result, and
    the spine's rotations stay unit (the conjugate inverts a unit quaternion only)."""
    local, root, off, rng = _pose(2)
    target, _ = _swung_target(local, root, off, rng, 15.0)
    nudged = local + rng.normal(0, 1e-7, local.shape)
    for passes in (3, 8):
        monkeypatch.setattr(limb_ik, "SPINE_PASSES", passes)
        a, _ = fk(limb_ik.reach_head_local(local, root, off, target), root, off)
        b, _ = fk(limb_ik.reach_head_local(nudged, root, off, target), root, off)
        assert np.abs(a - b).max() < 1e-5
        got = limb_ik.reach_head_local(nudged, root, off, target)
        np.testing.assert_allclose(np.linalg.norm(got[sorted(SPINE)], axis=-1), 1.0, atol=1e-12)
