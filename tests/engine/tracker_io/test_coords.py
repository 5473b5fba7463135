"""Axis conventions: the quaternion rule agrees with conjugating rotation matrices."""

from __future__ import annotations

import numpy as np
import pytest

from engine.errors import UserError
from engine.kinematics import quaternion as Q
from engine.tracker_io.coords import AXES, from_project, to_project, wxyz_to_xyzw, xyzw_to_wxyz


def _random_quats(n: int, seed: int = 0) -> np.ndarray:
    q = np.random.default_rng(seed).normal(size=(n, 4))
    return q / np.linalg.norm(q, axis=-1, keepdims=True)


@pytest.mark.parametrize("conv", ["unity", "openxr", "project"])
def test_rotation_conversion_is_conjugation_by_the_axis_matrix(conv):
    q = _random_quats(50)
    _, qc = from_project(np.zeros((50, 3)), q, conv)
    m = AXES[conv]
    want = m @ Q.to_matrix(q) @ m.T  # the same physical rotation written in the other axes
    np.testing.assert_allclose(Q.to_matrix(qc), want, atol=1e-12)


@pytest.mark.parametrize("conv", ["unity", "openxr"])
def test_round_trip(conv):
    rng = np.random.default_rng(1)
    p, q = rng.normal(size=(20, 3)), _random_quats(20, 1)
    pc, qc = from_project(p, q, conv)
    p2, q2 = to_project(pc, qc, conv)
    np.testing.assert_allclose(p2, p, atol=1e-12)
    np.testing.assert_allclose(q2, q, atol=1e-12)


def test_unity_and_openxr_axes_mean_what_the_docs_say():
    up, forward, left = np.array([0, 0, 1.0]), np.array([0, -1.0, 0]), np.array([1.0, 0, 0])
    ident = np.array([1.0, 0, 0, 0])
    # Unity: +Y up, +Z forward, +X right (left-handed)
    assert np.allclose(from_project(up, ident, "unity")[0], [0, 1, 0])
    assert np.allclose(from_project(forward, ident, "unity")[0], [0, 0, 1])
    assert np.allclose(from_project(left, ident, "unity")[0], [-1, 0, 0])
    assert np.linalg.det(AXES["unity"]) == pytest.approx(-1.0)
    # OpenXR: +Y up, -Z forward, +X right (right-handed)
    assert np.allclose(from_project(forward, ident, "openxr")[0], [0, 0, -1])
    assert np.allclose(from_project(left, ident, "openxr")[0], [-1, 0, 0])
    assert np.linalg.det(AXES["openxr"]) == pytest.approx(1.0)


def test_a_turn_to_the_left_stays_a_turn_to_the_left_in_unity():
    """Yaw 90 degrees about up turns forward to the left, in every convention."""
    yaw = Q.from_axis_angle(np.array([0, 0, 1.0]), np.pi / 2)
    fwd_c, q_c = from_project(np.array([0, -1.0, 0]), yaw, "unity")
    turned = Q.to_matrix(q_c) @ fwd_c
    left_c = from_project(np.array([1.0, 0, 0]), yaw, "unity")[0]
    np.testing.assert_allclose(turned, left_c, atol=1e-12)


def test_quaternion_order_helpers_and_unknown_convention():
    q = np.array([0.1, 0.2, 0.3, 0.9])
    np.testing.assert_array_equal(wxyz_to_xyzw(xyzw_to_wxyz(q)), q)
    assert xyzw_to_wxyz(q)[0] == 0.9
    with pytest.raises(UserError, match="unknown coordinate convention 'zup'"):
        to_project(np.zeros(3), np.array([1.0, 0, 0, 0]), "zup")
