"""Kinematics against upc-pymotion and against poses computed by hand."""

from __future__ import annotations

import numpy as np
import pymotion.rotations.dual_quat_np as pm_dq
import pymotion.rotations.quat_np as pm_q
import torch
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays
from pymotion.ops import skeleton_np

from engine import skeleton as sk
from engine.kinematics import features as Fe
from engine.kinematics import quaternion as Q
from engine.kinematics.fk import fk, fk_joints, fk_matrices, local_from_global
from engine.kinematics.root import place_root, root_displacement, root_increment

RNG = np.random.default_rng(3)
PARENTS_PM = np.array([0] + list(sk.PARENTS[1:]))


def _random_quats(*shape):
    return Q.normalize(RNG.normal(size=shape + (4,)))


def test_rotate_matches_matrix_and_pymotion():
    q = _random_quats(50)
    v = RNG.normal(size=(50, 3))
    by_matrix = np.einsum("nij,nj->ni", Q.to_matrix(q), v)
    np.testing.assert_allclose(Q.rotate(q, v), by_matrix, atol=1e-12)
    np.testing.assert_allclose(Q.rotate(q, v), pm_q.mul_vec(q, v), atol=1e-12)
    qt, vt = torch.tensor(q), torch.tensor(v)
    np.testing.assert_allclose(Q.rotate(qt, vt).numpy(), by_matrix, atol=1e-12)


def test_mul_matches_pymotion_numpy_and_torch():
    a, b = _random_quats(30), _random_quats(30)
    np.testing.assert_allclose(Q.mul(a, b), pm_q.mul(a, b), atol=1e-12)
    np.testing.assert_allclose(Q.mul(torch.tensor(a), torch.tensor(b)).numpy(), pm_q.mul(a, b), atol=1e-12)


def test_hand_computed_quarter_turn():
    q = Q.from_axis_angle(np.array([0.0, 0.0, 1.0]), np.pi / 2)  # +90 deg about Z
    np.testing.assert_allclose(Q.rotate(q, np.array([1.0, 0, 0])), [0, 1, 0], atol=1e-12)
    np.testing.assert_allclose(np.degrees(Q.angle(q, Q.identity(()))), 90.0)


def test_heading_keeps_only_yaw():
    yaw = Q.from_axis_angle(np.array([0.0, 0, 1]), 0.7)
    tilt = Q.from_axis_angle(np.array([1.0, 0, 0]), 0.3)
    h = Q.heading(Q.mul(yaw, tilt))
    np.testing.assert_allclose(Q.canonicalize(h), Q.canonicalize(yaw), atol=1e-9)


def test_fk_matches_pymotion_numpy_and_torch():
    rot = _random_quats(7, sk.NUM_JOINTS)
    root = RNG.normal(size=(7, 3))
    ours, grot = fk(rot, root, sk.REST_OFFSETS)
    theirs, _ = skeleton_np.fk(rot, root, sk.REST_OFFSETS, PARENTS_PM)
    np.testing.assert_allclose(ours, theirs, atol=1e-6)
    ours_t, _ = fk(torch.tensor(rot), torch.tensor(root), sk.REST_OFFSETS)
    np.testing.assert_allclose(ours_t.numpy(), ours, atol=1e-12)
    np.testing.assert_allclose(
        local_from_global(grot), rot * np.sign(rot[..., :1] * local_from_global(grot)[..., :1]), atol=1e-9
    )


def test_fk_joints_equals_the_rows_of_full_fk():
    rot = _random_quats(1, sk.NUM_JOINTS)[0]
    root = RNG.normal(size=3)
    offsets = sk.REST_OFFSETS * 1.3
    pos, grot = fk(rot, root, offsets)
    joints = [sk.JOINT_INDEX["lwrist"], 0, sk.JOINT_INDEX["upperneck"], sk.JOINT_INDEX["rtoe"], 0]
    p, r = fk_joints(rot, root, offsets, joints)
    np.testing.assert_allclose(p, pos[joints], atol=1e-12)
    np.testing.assert_allclose(r, grot[joints], atol=1e-12)
    p_all, _ = fk_joints(rot, root, offsets, range(sk.NUM_JOINTS))
    np.testing.assert_allclose(p_all, pos, atol=1e-12)


def test_fk_hand_computed_elbow_bend():
    """Rest pose plus a 90 degree elbow bend about Z: the wrist moves from +X to -Y of the elbow."""
    rot = Q.identity((sk.NUM_JOINTS,))
    rot[sk.JOINT_INDEX["lelbow"]] = Q.from_axis_angle(np.array([0.0, 0, 1]), -np.pi / 2)
    pos, _ = fk(rot, np.zeros(3), sk.REST_OFFSETS)
    e, w = sk.JOINT_INDEX["lelbow"], sk.JOINT_INDEX["lwrist"]
    off = sk.REST_OFFSETS[w]
    np.testing.assert_allclose(pos[w] - pos[e], [off[1], -off[0], off[2]], atol=1e-12)
    rest = sk.Skeleton.canonical().rest_positions()
    np.testing.assert_allclose(pos[: sk.JOINT_INDEX["lwrist"]], rest[: sk.JOINT_INDEX["lwrist"]], atol=1e-12)


def test_encoder_input_matches_pymotion_root_dual_quat():
    rot = _random_quats(5, sk.NUM_JOINTS)
    disp = RNG.normal(size=(5, 3)) * 0.01
    dq = Fe.encoder_input(rot, disp, sk.REST_OFFSETS)
    ref = skeleton_np.to_root_dual_quat(rot, np.zeros((5, 3)), PARENTS_PM, sk.REST_OFFSETS)
    # pymotion's root-space DQ for joints 1..; slot 0 is ours (root increment + displacement)
    ref = np.where(ref[..., :1] < 0, -ref, ref)
    np.testing.assert_allclose(dq[:, 1:], ref[:, 1:], atol=1e-6)
    r0, t0 = pm_dq.to_rotation_translation(dq[:, 0])
    np.testing.assert_allclose(np.abs((r0 * Q.canonicalize(rot[:, 0])).sum(-1)), 1.0, atol=1e-9)
    np.testing.assert_allclose(t0, disp, atol=1e-9)
    assert (dq[..., 0] >= 0).all()
    np.testing.assert_allclose(
        Fe.encoder_input(torch.tensor(rot), torch.tensor(disp), sk.REST_OFFSETS).numpy(), dq, atol=1e-9
    )


def test_heights_from_root_space_positions_are_those_of_a_world_fk(synthetic_motion):
    m = synthetic_motion
    rot, disp = Fe.pose_from_motion(m.local_rot, m.root_pos)
    for kit in (np.asarray, torch.tensor):
        lr, rp = kit(m.local_rot), kit(m.root_pos)
        pos, _ = Fe.root_space_fk(kit(rot), sk.REST_OFFSETS)
        want = np.asarray(Fe.heights(lr, rp, sk.REST_OFFSETS))
        got = np.asarray(Fe.heights_from_root_space(lr[:, 0], rp, pos))
        assert got.shape == want.shape and np.ptp(want) > 0.1
        np.testing.assert_allclose(got, want, atol=1e-12)


def test_pose_round_trip_recovers_motion(synthetic_motion):
    m = synthetic_motion
    rot, disp = Fe.pose_from_motion(m.local_rot, m.root_pos)
    local, root = Fe.motion_from_pose(rot[1:], disp[1:], start_root_rot=m.local_rot[0, 0], start_pos=m.root_pos[0])
    np.testing.assert_allclose(root, m.root_pos[1:], atol=1e-9)
    ang = Q.angle(local, m.local_rot[1:])
    assert ang.max() < 1e-6


def test_mirror_twice_is_identity_and_swaps_sides(synthetic_motion):
    m = synthetic_motion
    rot, pos, off = Fe.mirror_motion(m.local_rot, m.root_pos, m.skeleton.offsets)
    p_m, _ = fk(rot, pos, off)
    p, _ = fk(m.local_rot, m.root_pos, m.skeleton.offsets)
    idx = list(sk.MIRROR_INDEX)
    np.testing.assert_allclose(p_m, p[:, idx] * np.array([-1.0, 1, 1]), atol=1e-9)
    rot2, pos2, off2 = Fe.mirror_motion(rot, pos, off)
    np.testing.assert_allclose(rot2, m.local_rot, atol=1e-12)
    np.testing.assert_allclose(off2, m.skeleton.offsets)


@settings(max_examples=50, deadline=None)
@given(arrays(np.float64, (4,), elements=st.floats(-1, 1)).filter(lambda a: np.linalg.norm(a) > 0.1))
def test_canonicalize_same_rotation(q):
    q = Q.normalize(q)
    c = Q.canonicalize(q)
    assert c[0] >= 0
    np.testing.assert_allclose(Q.to_matrix(c), Q.to_matrix(q), atol=1e-9)


def test_fk_matrices_match_the_quaternion_fk_numpy_and_torch():
    q = _random_quats(3, sk.NUM_JOINTS)
    r = RNG.normal(size=(3, 3))
    off = sk.REST_OFFSETS * RNG.uniform(0.8, 1.2, size=(3, sk.NUM_JOINTS, 1))  # per-frame proportions
    p_ref, r_ref = fk(q, r, off)
    p_np, m_np = fk_matrices(Q.to_matrix(q), r, off)
    np.testing.assert_allclose(p_np, p_ref, atol=1e-12)
    np.testing.assert_allclose(m_np, Q.to_matrix(r_ref), atol=1e-12)
    p_t, m_t = fk_matrices(Q.to_matrix(torch.tensor(q)), torch.tensor(r), off)
    np.testing.assert_allclose(p_t.numpy(), p_ref, atol=1e-12)
    np.testing.assert_allclose(m_t.numpy(), Q.to_matrix(r_ref), atol=1e-12)


def test_fk_by_levels_matches_a_joint_by_joint_loop():
    q = _random_quats(4, sk.NUM_JOINTS)
    r = RNG.normal(size=(4, 3))
    pos, rot = fk(q, r, sk.REST_OFFSETS)
    for j in range(1, sk.NUM_JOINTS):  # independent: world = parent world * local
        p = sk.PARENTS[j]
        np.testing.assert_allclose(rot[:, j], pm_q.mul(rot[:, p], q[:, j]), atol=1e-12)
        np.testing.assert_allclose(
            pos[:, j], pos[:, p] + pm_q.mul_vec(rot[:, p], np.broadcast_to(sk.REST_OFFSETS[j], (4, 3))), atol=1e-12
        )


def test_the_root_displacement_alone_has_the_bits_of_the_root_increments():
    prev_rot, rot = _random_quats(50), _random_quats(50)
    prev_pos, pos = RNG.normal(size=(50, 3)), RNG.normal(size=(50, 3))
    for conv in (np.asarray, lambda x: torch.tensor(x, dtype=torch.float32)):
        args = [conv(x) for x in (prev_rot, prev_pos, rot, pos)]
        want = root_increment(*args)[1]
        got = root_displacement(args[0], args[1], args[3])
        assert type(got) is type(want) and (np.asarray(got) == np.asarray(want)).all()


def test_root_integration_round_trips_numpy_and_torch():
    prev_rot, rot = _random_quats(5), _random_quats(5)
    prev_pos, pos = RNG.normal(size=(5, 3)), RNG.normal(size=(5, 3))
    rot0, disp = root_increment(prev_rot, prev_pos, rot, pos)
    back_rot, back_pos = place_root(Q.heading(prev_rot), rot0, prev_pos, disp)
    np.testing.assert_allclose(back_pos, pos, atol=1e-12)
    np.testing.assert_allclose(Q.canonicalize(back_rot), Q.canonicalize(rot), atol=1e-12)
    t = [torch.tensor(x) for x in (prev_rot, prev_pos, rot0, disp)]
    t_rot, t_pos = place_root(Q.heading(t[0]), t[2], t[1], t[3])
    np.testing.assert_allclose(t_pos.numpy(), pos, atol=1e-12)


def test_the_root_rule_is_the_same_on_matrices_and_with_a_hip_tracker():
    """The solver's chain places the root with matrices, the reference with quaternions:
    one rule; a hip tracker's rotation and position replace each part on its own."""
    prev_rot, rot0 = _random_quats(4), _random_quats(4)
    prev_pos, disp = RNG.normal(size=(4, 3)), RNG.normal(size=(4, 3))
    h = Q.heading(prev_rot)
    q_rot, q_pos = place_root(h, rot0, prev_pos, disp)
    m_rot, m_pos = place_root(Q.to_matrix(h), Q.to_matrix(rot0), prev_pos, disp)
    np.testing.assert_allclose(m_rot, Q.to_matrix(q_rot), atol=1e-12)
    np.testing.assert_allclose(m_pos, q_pos, atol=1e-12)
    hip_rot, hip_pos = _random_quats(4), RNG.normal(size=(4, 3))
    r, p = place_root(h, rot0, prev_pos, disp, rotation=hip_rot)
    assert (r == hip_rot).all() and (p == q_pos).all()
    r, p = place_root(h, rot0, prev_pos, disp, position=hip_pos)
    assert (r == q_rot).all() and (p == hip_pos).all()
    r, p = place_root(h, rot0)  # the rotation alone
    assert (r == q_rot).all() and p is None


def test_ancestors_and_children_follow_the_parent_list():
    from engine.kinematics.fk import ancestors, children

    parents = (-1, 0, 1, 1, 3, 0)
    assert ancestors(parents, 4) == [4, 3, 1, 0] and ancestors(parents, 0) == [0]
    assert ancestors((0, 0, 1), 2) == [2, 1, 0]  # a root listed as its own parent
    assert children(parents, 1) == [2, 3] and children(parents, 2) == [] and children((0, 0, 1), 0) == [1]
    assert ancestors(sk.PARENTS, sk.JOINT_INDEX["lwrist"])[-1] == 0
