"""The head tracker's turn about the neck shared with the lower neck
(engine.solver.limb_ik.share_neck_twist, setting ``neck_twist_share``)."""

from __future__ import annotations

import numpy as np
import pytest

from engine import skeleton as sk
from engine.errors import UserError
from engine.kinematics import quaternion as Q
from engine.kinematics.fk import fk, fk_positions
from engine.solver import OptimizerSettings, limb_ik

HEAD, NECK = sk.JOINT_INDEX["upperneck"], sk.JOINT_INDEX["lowerneck"]


def _pose(seed: int):
    rng = np.random.default_rng(seed)
    local = Q.normalize(np.array([1.0, 0, 0, 0]) + rng.normal(0, 0.25, size=(sk.NUM_JOINTS, 4)))
    off = sk.Skeleton.canonical().offsets
    root = np.array([0.1, -0.2, 0.95])
    return local, root, off, rng


def _neck_axis(local, root, off):
    _, rots = fk(local, root, off)
    axis = Q.rotate(rots[NECK], off[HEAD])
    return axis / np.linalg.norm(axis), rots


@pytest.mark.parametrize("seed", range(6))
@pytest.mark.parametrize("share", [0.25, 0.5, 1.0])
def test_the_lower_neck_takes_its_share_of_the_twist_and_the_head_still_meets_its_tracker(seed, share):
    local, root, off, rng = _pose(seed)
    axis, rots = _neck_axis(local, root, off)
    twist = np.radians(rng.uniform(-120, 120))
    swing_axis = np.cross(axis, rng.normal(size=3))
    swing = Q.from_axis_angle(swing_axis / np.linalg.norm(swing_axis), np.radians(rng.uniform(-30, 30)))
    # the tracker: the decoded head turned about the neck, then tilted off it
    target = Q.mul(swing, Q.mul(Q.from_axis_angle(axis, twist), rots[HEAD]))
    base_local, base_pos = limb_ik.finish(local, root, off, {}, {HEAD: target})
    got_local, got_pos = limb_ik.finish(local, root, off, {}, {HEAD: target}, neck_twist_share=share)
    _, got_rots = fk(got_local, root, off)
    assert np.degrees(Q.angle(got_rots[HEAD], target)) < 1e-5, "the head meets its tracker exactly"
    np.testing.assert_allclose(got_pos, base_pos, atol=1e-9, err_msg="a turn about the neck bone moves no joint")
    changed = [j for j in range(sk.NUM_JOINTS) if not np.allclose(got_local[j], base_local[j], atol=1e-9)]
    assert set(changed) <= {NECK, HEAD}
    # the lower neck turned about the neck bone by the share of the correction's twist
    turn = Q.mul(fk(got_local, root, off)[1][NECK], Q.conjugate(rots[NECK]))
    turn = turn if turn[0] >= 0 else -turn
    delta = Q.mul(target, Q.conjugate(rots[HEAD]))
    expected = 2 * np.arctan2(delta[1:] @ axis, delta[0])
    expected = (expected + np.pi) % (2 * np.pi) - np.pi
    np.testing.assert_allclose(np.cross(turn[1:], axis), 0.0, atol=1e-9, err_msg="the turn is about the neck bone")
    assert 2 * np.arctan2(turn[1:] @ axis, turn[0]) == pytest.approx(share * expected, abs=1e-9)


def test_a_tilt_without_twist_leaves_the_lower_neck_alone_and_share_zero_is_the_old_step():
    local, root, off, rng = _pose(11)
    axis, rots = _neck_axis(local, root, off)
    side = np.cross(axis, [0.3, 0.5, 0.8])
    target = Q.mul(Q.from_axis_angle(side / np.linalg.norm(side), np.radians(25.0)), rots[HEAD])
    got = limb_ik.finish(local, root, off, {}, {HEAD: target}, neck_twist_share=0.5)[0]
    np.testing.assert_allclose(got[NECK], local[NECK], atol=1e-9)
    turned = Q.mul(Q.from_axis_angle(axis, np.radians(40.0)), rots[HEAD])
    np.testing.assert_array_equal(limb_ik.share_neck_twist(local, root, off, turned, 0.0), local)
    # without a head target nothing is shared
    hand = {sk.JOINT_INDEX["lwrist"]: turned}
    np.testing.assert_array_equal(
        limb_ik.finish(local, root, off, {}, hand, 0.5)[0], limb_ik.finish(local, root, off, {}, hand)[0]
    )


@pytest.mark.parametrize("bad", [-0.1, 1.5, float("nan")])
def test_neck_twist_share_is_validated(bad):
    with pytest.raises(UserError, match="neck_twist_share"):
        OptimizerSettings(neck_twist_share=bad)


def test_positions_only_fk_gives_the_positions_of_fk_bit_for_bit():
    rng = np.random.default_rng(7)
    offsets = sk.Skeleton.canonical().offsets
    for shape in ((), (5,)):
        # slightly non-unit, as the decoder's float32 rotations are
        local = rng.normal(size=shape + (sk.NUM_JOINTS, 4)).astype(np.float32).astype(np.float64)
        local /= np.linalg.norm(local, axis=-1, keepdims=True) * (1.0 + 1e-6)
        root = rng.normal(size=shape + (3,))
        assert np.array_equal(fk_positions(local, root, offsets), fk(local, root, offsets)[0])
