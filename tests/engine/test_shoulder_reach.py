"""A wrist tracker beyond the straight arm: the clavicle turns the shoulder towards it
before the arm's two-bone reach (engine.solver.limb_ik.reach_local, setting
``shoulder_reach``)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from engine import skeleton as sk
from engine.errors import UserError
from engine.kinematics import quaternion as Q
from engine.kinematics.fk import fk
from engine.solver import OptimizerSettings, limb_ik

J = sk.JOINT_INDEX
ARM = {
    "l": [J["lclavicle"], J["lshoulder"], J["lelbow"], J["lwrist"]],
    "r": [J["rclavicle"], J["rshoulder"], J["relbow"], J["rwrist"]],
}


def _pose(seed: int):
    rng = np.random.default_rng(seed)
    local = Q.normalize(np.array([1.0, 0, 0, 0]) + rng.normal(0, 0.2, size=(sk.NUM_JOINTS, 4)))
    off = sk.Skeleton.canonical().offsets
    return local, np.array([0.1, -0.2, 0.95]), off, rng


def _beyond(side: str, local, root, off, extra: float, rng):
    """A wrist target ``extra`` metres beyond the straight arm, mostly across the clavicle."""
    clav, sh, el, wr = ARM[side]
    pos, _ = fk(local, root, off)
    length = np.linalg.norm(off[el]) + np.linalg.norm(off[wr])
    out = pos[sh] - pos[clav]
    out /= np.linalg.norm(out)
    d = rng.normal(size=3)
    d -= (d @ out) * out  # across the clavicle, where its turn moves the shoulder most
    d = d / np.linalg.norm(d) + 0.3 * out
    d /= np.linalg.norm(d)
    return wr, pos[sh] + d * (length + extra)


def _clavicle_turn_deg(before, after, root, off, clav):
    _, r0 = fk(before, root, off)
    _, r1 = fk(after, root, off)
    return np.degrees(Q.angle(r1[clav], r0[clav]))


@pytest.mark.parametrize("seed", range(8))
@pytest.mark.parametrize("side", ["l", "r"])
def test_a_wrist_a_few_centimetres_beyond_the_arm_lands_on_its_tracker(seed, side):
    local, root, off, rng = _pose(seed)
    wrist, target = _beyond(side, local, root, off, rng.uniform(0.01, 0.04), rng)
    without = fk(limb_ik.reach_local(local, root, off, {wrist: target}), root, off)[0]
    got = limb_ik.reach_local(local, root, off, {wrist: target}, shoulder_deg=40.0)
    pos = fk(got, root, off)[0]
    assert np.linalg.norm(without[wrist] - target) > 0.009, "the arm alone falls short"
    assert np.linalg.norm(pos[wrist] - target) < 2e-3, "the straight arm (1 mm slack) reaches it"
    changed = {j for j in range(sk.NUM_JOINTS) if not np.allclose(got[j], local[j], atol=1e-12)}
    assert changed <= set(ARM[side]) and ARM[side][0] in changed
    others = [j for j in range(sk.NUM_JOINTS) if j not in ARM[side][1:]]
    np.testing.assert_allclose(pos[others], without[others], atol=1e-12, err_msg="the clavicle turns in place")
    _, rots = fk(got, root, off)
    _, rots0 = fk(local, root, off)
    assert np.degrees(Q.angle(rots[wrist], rots0[wrist])) < 1e-4, "the hand keeps its world rotation"


@pytest.mark.parametrize("seed", range(4))
def test_the_turn_stops_at_its_limit_and_still_brings_the_wrist_nearer(seed):
    local, root, off, rng = _pose(seed)
    wrist, target = _beyond("l", local, root, off, 0.3, rng)
    without = fk(limb_ik.reach_local(local, root, off, {wrist: target}), root, off)[0]
    got = limb_ik.reach_local(local, root, off, {wrist: target}, shoulder_deg=10.0)
    assert _clavicle_turn_deg(local, got, root, off, ARM["l"][0]) == pytest.approx(10.0, abs=1e-6)
    pos = fk(got, root, off)[0]
    assert np.linalg.norm(pos[wrist] - target) < np.linalg.norm(without[wrist] - target) - 1e-3


def test_within_reach_and_for_legs_nothing_changes():
    local, root, off, rng = _pose(3)
    pos, _ = fk(local, root, off)
    inside = {J["lwrist"]: pos[J["lelbow"]] + 0.5 * (pos[J["lwrist"]] - pos[J["lelbow"]])}
    np.testing.assert_array_equal(
        limb_ik.reach_local(local, root, off, inside, shoulder_deg=30.0), limb_ik.reach_local(local, root, off, inside)
    )
    far_foot = {J["lankle"]: pos[J["lhip"]] + np.array([0.0, 0.0, -2.0])}
    np.testing.assert_array_equal(
        limb_ik.reach_local(local, root, off, far_foot, shoulder_deg=30.0),
        limb_ik.reach_local(local, root, off, far_foot),
    )


@pytest.mark.parametrize("bad", [-1.0, 90.0, float("nan")])
def test_shoulder_reach_is_validated(bad):
    with pytest.raises(UserError, match="shoulder_reach"):
        OptimizerSettings(shoulder_reach=bad)


def test_a_constraint_on_a_clavicle_turns_the_shoulder_step_off():
    from engine.constraints import PinConstraint
    from engine.methods import get_method
    from engine.motion.retarget import load_motion
    from engine.tracking import simulate

    repo = Path(__file__).resolve().parents[2]
    if not (repo / "assets" / "models" / "vae.pt").is_file():
        pytest.skip("shipped model not found in assets/models")
    clip = load_motion(repo / "assets" / "clips" / "example.bvh").slice(0, 2)
    method = get_method("dragposer")
    method.reset(clip.skeleton, clip.fps)
    frame = simulate(clip, "6").frame(0)
    assert method.plan(frame).shoulder_deg == OptimizerSettings().shoulder_reach > 0
    method.add_constraint(PinConstraint(name="pin", joint="rclavicle", position=clip.positions()[0, J["rclavicle"]]))
    assert method.plan(frame).shoulder_deg == 0.0
