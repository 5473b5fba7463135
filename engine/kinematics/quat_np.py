"""Quaternion maths on numpy arrays only (no torch), for code that must not import torch
(the Qt widgets) and as the numpy backend of :mod:`engine.kinematics.quaternion`.

Quaternions are ``(..., 4)`` arrays in ``(w, x, y, z)`` order; shapes broadcast.
"""

from __future__ import annotations

import math

import numpy as np

_CONJ = np.array([1.0, -1.0, -1.0, -1.0])


def _product_tensors() -> tuple[np.ndarray, np.ndarray]:
    """Constant tensors that turn the products below into one matmul each.

    ``MUL[4 * j + k, i]``: coefficient of ``a_j b_k`` in ``(a * b)_i``;
    ``MAT[4 * j + k, 3 * r + c]``: coefficient of ``q_j q_k`` in ``R(q)[r, c]`` (unit q).
    Numpy's per-call overhead dominates on the small arrays used here, so two calls (an
    outer product and a matmul) beat the two dozen elementwise ones of the formulas."""
    e = np.eye(4)
    mul = np.stack([_mul_formula(e[j], e[k]) for j in range(4) for k in range(4)])
    mat = np.zeros((16, 9))
    for j in range(4):
        for k in range(4):
            # R v = q (0, v) q*, bilinear in q: the (j, k) coefficient, symmetrised
            qa, qb = e[j], e[k]
            cols = [_mul_formula(_mul_formula(qa, np.r_[0.0, v]), qb * _CONJ)[1:] for v in np.eye(3)]
            mat[4 * j + k] = np.stack(cols, axis=1).reshape(9)
    mat = 0.5 * (mat + mat.reshape(4, 4, 9).transpose(1, 0, 2).reshape(16, 9))
    return mul, mat


def _mul_formula(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    w0, x0, y0, z0 = a
    w1, x1, y1, z1 = b
    return np.array([w0 * w1 - x0 * x1 - y0 * y1 - z0 * z1, w0 * x1 + x0 * w1 + y0 * z1 - z0 * y1,
                     w0 * y1 - x0 * z1 + y0 * w1 + z0 * x1, w0 * z1 + x0 * y1 - y0 * x1 + z0 * w1])


_MUL, _MAT = _product_tensors()


def mul(q0: np.ndarray, q1: np.ndarray) -> np.ndarray:
    """Hamilton product ``q0 * q1``, ``(..., 4)``.

    Two single quaternions ``(4,)`` take a scalar path: at that size numpy's per-call
    overhead costs more than the arithmetic (IK multiplies many single rotations)."""
    if np.ndim(q0) == 1 and np.ndim(q1) == 1:
        w0, x0, y0, z0 = q0.tolist() if isinstance(q0, np.ndarray) else q0
        w1, x1, y1, z1 = q1.tolist() if isinstance(q1, np.ndarray) else q1
        return np.array([w0 * w1 - x0 * x1 - y0 * y1 - z0 * z1, w0 * x1 + x0 * w1 + y0 * z1 - z0 * y1,
                         w0 * y1 - x0 * z1 + y0 * w1 + z0 * x1, w0 * z1 + x0 * y1 - y0 * x1 + z0 * w1])
    q0, q1 = np.asarray(q0), np.asarray(q1)
    return (q0[..., :, None] * q1[..., None, :]).reshape(np.broadcast_shapes(q0.shape, q1.shape)[:-1] + (16,)) @ _MUL


def rotate(q: np.ndarray, v: np.ndarray) -> np.ndarray:
    """Rotate vectors ``v (..., 3)`` by unit quaternions ``q (..., 4)`` (one ``(4,)`` by
    one ``(3,)`` takes a scalar path, as in :func:`mul`)."""
    if np.ndim(q) == 1 and np.ndim(v) == 1:
        w, x, y, z = q.tolist() if isinstance(q, np.ndarray) else q
        a, b, c = v.tolist() if isinstance(v, np.ndarray) else v
        tx, ty, tz = 2.0 * (y * c - z * b), 2.0 * (z * a - x * c), 2.0 * (x * b - y * a)
        return np.array([a + w * tx + y * tz - z * ty, b + w * ty + z * tx - x * tz, c + w * tz + x * ty - y * tx])
    return (to_matrix(q) @ np.asarray(v)[..., None])[..., 0]


def conjugate(q: np.ndarray) -> np.ndarray:
    """Inverse of a unit quaternion, ``(..., 4)``."""
    return q * _CONJ


def to_matrix(q: np.ndarray) -> np.ndarray:
    """Unit quaternions ``(..., 4)`` to rotation matrices ``(..., 3, 3)`` (the quadratic
    form ``R = q (0, v) q*``; it scales by ``|q|^2`` for non-unit input)."""
    q = np.asarray(q)
    return ((q[..., :, None] * q[..., None, :]).reshape(q.shape[:-1] + (16,)) @ _MAT).reshape(q.shape[:-1] + (3, 3))


def heading(q: np.ndarray) -> np.ndarray:
    """Yaw-only part of ``q (..., 4)``: the rotation about +Z that turns the rest forward
    (-Y) onto the horizontal projection of ``q``'s forward, ``(..., 4)``."""
    q = np.asarray(q)
    if q.ndim == 1:  # one quaternion: scalar arithmetic (numpy's per-call overhead dominates)
        fx, fy, _ = rotate(q, (0.0, -1.0, 0.0)).tolist()
        half = 0.5 * math.atan2(fx, -fy)
        return np.array([math.cos(half), 0.0, 0.0, math.sin(half)])
    fw = rotate(q, np.broadcast_to(np.array([0.0, -1.0, 0.0]), q.shape[:-1] + (3,)))
    half = 0.5 * np.arctan2(fw[..., 0], -fw[..., 1])
    z = np.zeros_like(half)
    return np.stack((np.cos(half), z, z, np.sin(half)), axis=-1)
