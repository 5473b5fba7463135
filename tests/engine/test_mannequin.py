"""The exported body: a capsule per bone, outward-facing, skinned so that a bend blends
the two joints that meet there (engine/motion/mannequin.py)."""

from __future__ import annotations

import numpy as np

from engine import skeleton as sk
from engine.motion.mannequin import AROUND, BONE_RADIUS, bones_of, skinned_mannequin


def _canonical():
    rest = sk.Skeleton.canonical().rest_positions()
    ends = {sk.JOINT_INDEX[n]: off for n, off in sk.END_SITES.items()}
    radius = {sk.JOINT_INDEX[n]: r for n, r in BONE_RADIUS.items()}
    bones = bones_of(rest, sk.PARENTS, ends, radius)
    return rest, bones, skinned_mannequin(bones, sk.PARENTS)


def test_one_capsule_per_bone_and_end_site_with_the_body_view_s_radii():
    _, bones, _ = _canonical()
    assert len(bones) == sk.NUM_JOINTS - 1 + len(sk.END_SITES)
    thigh = next(b for b in bones if b.child == sk.JOINT_INDEX["lknee"])
    assert thigh.radius == BONE_RADIUS["lknee"] and thigh.joint == sk.JOINT_INDEX["lhip"]


def test_faces_point_outwards_and_normals_are_unit():
    _, _, mesh = _canonical()
    tri = mesh.indices.reshape(-1, 3)
    p = mesh.positions[tri].astype(float)
    face = np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0])
    assert (np.einsum("ij,ij->i", face, mesh.normals[tri].sum(1)) > 0).all()
    assert np.allclose(np.linalg.norm(mesh.normals, axis=1), 1.0, atol=1e-6)


def test_a_bend_blends_the_joints_half_and_half_and_the_middle_is_rigid():
    rest, bones, mesh = _canonical()
    elbow, shoulder, wrist = sk.JOINT_INDEX["lelbow"], sk.JOINT_INDEX["lshoulder"], sk.JOINT_INDEX["lwrist"]

    def weight_of(vertices, joint):
        return np.where(mesh.joints[vertices] == joint, mesh.weights[vertices], 0.0).sum(1)

    assert np.allclose(mesh.weights.sum(1), 1.0, atol=1e-6)
    at_elbow = np.linalg.norm(mesh.positions - rest[elbow], axis=1) < BONE_RADIUS["lelbow"] * 1.01
    # the forearm capsule's rim at the elbow is moved half by the elbow, half by the shoulder
    forearm_rim = at_elbow & (weight_of(np.arange(len(mesh.positions)), elbow) > 0.4)
    assert forearm_rim.any()
    w_e = weight_of(np.flatnonzero(forearm_rim), elbow)
    w_s = weight_of(np.flatnonzero(forearm_rim), shoulder)
    assert np.allclose(w_e + w_s, 1.0, atol=1e-6)
    assert (np.abs(w_e - 0.5) < 1e-6).sum() >= 2 * AROUND  # both capsules' rings at the joint
    # half way along the forearm only the elbow moves it
    mid = (rest[elbow] + rest[wrist]) / 2
    middle = np.linalg.norm(mesh.positions - mid, axis=1) < BONE_RADIUS["lwrist"] * 1.05
    assert middle.sum() >= 12 and np.allclose(weight_of(np.flatnonzero(middle), elbow), 1.0)
