"""The numpy kit's single-rotation functions (``q*``/``v*``) against independent
computations: numpy's own vector maths, upc-pymotion's quaternions, Rodrigues' matrix
formula, and the defining properties of each construction."""

from __future__ import annotations

import math

import numpy as np
import pymotion.rotations.quat_np as pm_q
import pytest

from engine.kinematics import quat_np as QN

RNG = np.random.default_rng(11)


def _unit(n: int = 4) -> np.ndarray:
    q = RNG.normal(size=n)
    return q / np.linalg.norm(q)


def _rodrigues(axis: np.ndarray, angle: float) -> np.ndarray:
    """Rotation matrix of ``angle`` about the unit ``axis``, without quaternions."""
    k = np.array([[0.0, -axis[2], axis[1]], [axis[2], 0.0, -axis[0]], [-axis[1], axis[0], 0.0]])
    return np.eye(3) + math.sin(angle) * k + (1.0 - math.cos(angle)) * (k @ k)


def _same_rotation(q0, q1, tol: float = 1e-12) -> None:
    q0, q1 = np.asarray(q0, float), np.asarray(q1, float)
    assert min(np.abs(q0 - q1).max(), np.abs(q0 + q1).max()) < tol, (q0, q1)


def test_vector_functions_match_numpy():
    for _ in range(50):
        a, b = RNG.normal(size=3), RNG.normal(size=3)
        np.testing.assert_allclose(QN.vsub(a, b), a - b, rtol=0, atol=1e-15)
        assert QN.vdot(a, b) == pytest.approx(float(np.dot(a, b)), abs=1e-14)
        np.testing.assert_allclose(QN.vcross(a, b), np.cross(a, b), rtol=0, atol=1e-14)
        assert QN.vnorm(a) == pytest.approx(float(np.linalg.norm(a)), abs=1e-14)
        np.testing.assert_allclose(QN.vscale(a, 2.5), 2.5 * a, rtol=0, atol=1e-15)
        q = RNG.normal(size=4)
        assert QN.qnorm(q) == pytest.approx(float(np.linalg.norm(q)), abs=1e-14)
    assert all(isinstance(x, float) for x in QN.vcross((1.0, 0.0, 0.0), np.array([0.0, 1.0, 0.0])))


def test_product_conjugate_and_rotation_match_pymotion():
    for _ in range(50):
        q0, q1, v = _unit(), _unit(), RNG.normal(size=3)
        np.testing.assert_allclose(QN.qmul(q0, q1), pm_q.mul(q0[None], q1[None])[0], rtol=0, atol=1e-14)
        np.testing.assert_allclose(QN.qrotate(q0, v), pm_q.mul_vec(q0[None], v[None])[0], rtol=0, atol=1e-14)
        np.testing.assert_allclose(QN.qmul(q0, QN.qconj(q0)), QN.IDENTITY, rtol=0, atol=1e-15)
        # the array API's one-rotation path is the same arithmetic
        assert QN.mul(q0, q1).tolist() == list(QN.qmul(q0, q1))
        assert QN.rotate(q0, v).tolist() == list(QN.qrotate(q0, v))


def test_axis_angle_matches_rodrigues():
    for _ in range(30):
        axis, angle = _unit(3), float(RNG.uniform(-math.pi, math.pi))
        np.testing.assert_allclose(
            QN.to_matrix(np.array(QN.qaxis_angle(axis, angle))), _rodrigues(axis, angle), atol=1e-14
        )
        _same_rotation(QN.qabout(7.0 * axis, angle), QN.qaxis_angle(axis, angle))
    assert QN.qabout((0.0, 0.0, 0.0), 1.0) == QN.IDENTITY
    assert QN.qabout((1.0, 0.0, 0.0), 1e-13) == QN.IDENTITY


def test_between_turns_one_direction_onto_the_other_by_the_smallest_angle():
    for _ in range(50):
        u, v = RNG.normal(size=3) * 3.0, RNG.normal(size=3) * 0.2
        q = QN.qbetween(u, v)
        assert QN.qnorm(q) == pytest.approx(1.0, abs=1e-14)
        np.testing.assert_allclose(QN.qrotate(q, u / np.linalg.norm(u)), v / np.linalg.norm(v), atol=1e-14)
        cos_uv = np.dot(u, v) / np.linalg.norm(u) / np.linalg.norm(v)
        assert 2.0 * math.acos(min(1.0, abs(q[0]))) == pytest.approx(math.acos(cos_uv), abs=1e-7)
        assert abs(np.dot(q[1:], u)) < 1e-12 and abs(np.dot(q[1:], v)) < 1e-12  # the axis is u x v
    u = np.array([0.3, -0.2, 0.9])
    half = QN.qbetween(u, -u)
    assert abs(half[0]) < 1e-15 and abs(np.dot(half[1:], u)) < 1e-15  # a half turn about a perpendicular
    np.testing.assert_allclose(QN.qrotate(half, u), -u, atol=1e-14)
    assert QN.qbetween((0.0, 0.0, 0.0), u) == QN.IDENTITY
    _same_rotation(QN.qbetween(u, 2.0 * u), QN.IDENTITY)


def test_power_scales_the_angle_about_the_same_axis():
    for _ in range(30):
        axis, angle, t = _unit(3), float(RNG.uniform(0.1, 3.0)), float(RNG.uniform(-1.0, 1.0))
        q = QN.qaxis_angle(axis, angle)
        _same_rotation(QN.qpow(q, t), QN.qaxis_angle(axis, t * angle), 1e-12)
        half = QN.qpow(tuple(-x for x in q), 0.5)  # -q is the same rotation: the short way round
        _same_rotation(QN.qmul(half, half), q, 1e-12)


def test_twist_is_the_part_about_the_axis_and_the_rest_is_a_swing():
    for _ in range(50):
        q, axis = _unit(), RNG.normal(size=3)
        twist = QN.qtwist(q, axis)
        a = axis / np.linalg.norm(axis)
        assert np.linalg.norm(np.cross(twist[1:], a)) < 1e-14, "the twist turns about the axis"
        swing = QN.qmul(q, QN.qconj(twist))
        assert abs(np.dot(swing[1:], a)) < 1e-14, "what is left turns about an axis perpendicular to it"
        _same_rotation(QN.qmul(swing, twist), q, 1e-14)
    assert QN.qtwist(QN.qaxis_angle((1.0, 0.0, 0.0), math.pi), (0.0, 0.0, 1.0)) == QN.IDENTITY


def test_from_matrix_matches_pymotion_on_every_branch():
    angles = [0.3, 2.0, math.pi - 1e-9, math.pi]  # trace > 0 and the three diagonal branches
    for angle in angles:
        for axis in (_unit(3), np.array([1.0, 0.0, 0.0]), np.array([0.0, 1.0, 0.0]), np.array([0.0, 0.0, 1.0])):
            m = _rodrigues(axis, angle)
            q = QN.qfrom_matrix(m)
            assert all(isinstance(x, float) for x in q)
            _same_rotation(q, QN.qaxis_angle(axis, angle), 1e-12)
            _same_rotation(q, pm_q.from_matrix(m[None])[0], 1e-8)  # pymotion's route rounds more
            np.testing.assert_allclose(QN.to_matrix(np.array(q)), m, atol=1e-12)


def test_from_bases_maps_the_direction_and_the_plane():
    for _ in range(30):
        u0, w0, u1, w1 = (RNG.normal(size=3) for _ in range(4))
        q = QN.qfrom_bases(u0, w0, u1, w1)
        np.testing.assert_allclose(QN.qrotate(q, u0 / np.linalg.norm(u0)), u1 / np.linalg.norm(u1), atol=1e-12)
        n0, n1 = np.cross(u0, w0), np.cross(u1, w1)
        np.testing.assert_allclose(QN.qrotate(q, n0 / np.linalg.norm(n0)), n1 / np.linalg.norm(n1), atol=1e-12)
    q = QN.qfrom_bases((1.0, 0.0, 0.0), (2.0, 0.0, 0.0), (0.0, 1.0, 0.0), (0.0, 3.0, 0.0))  # no plane given
    np.testing.assert_allclose(QN.qrotate(q, (1.0, 0.0, 0.0)), (0.0, 1.0, 0.0), atol=1e-15)


def test_one_matrix_formula_for_numpy_and_torch_and_any_length():
    """Both kits share the quadratic form; :func:`QN.unit_to_matrix` normalises a
    quaternion of any length first and takes a zero one as the identity."""
    import torch

    from engine.kinematics import quaternion as Q

    axis, angle = _unit(3), 1.2
    q = np.array(QN.qaxis_angle(axis, angle))
    np.testing.assert_allclose(Q.to_matrix(torch.tensor(q)).numpy(), _rodrigues(axis, angle), atol=1e-12)
    np.testing.assert_allclose(
        Q.to_matrix(torch.tensor(q, dtype=torch.float32)).numpy(), _rodrigues(axis, angle), atol=1e-6
    )
    np.testing.assert_allclose(QN.unit_to_matrix(3.0 * q), _rodrigues(axis, angle), atol=1e-12)
    np.testing.assert_array_equal(QN.unit_to_matrix(np.zeros((2, 4))), np.broadcast_to(np.eye(3), (2, 3, 3)))
