"""The numpy quaternion and vector kit (no torch): for code that must not import torch
(the Qt widgets) and the numpy backend of :mod:`engine.kinematics.quaternion`.

Quaternions are ``(..., 4)`` arrays in ``(w, x, y, z)`` order; shapes broadcast.

Functions named ``q*`` and ``v*`` (:func:`qmul`, :func:`vcross`...) take *one* rotation
``(w, x, y, z)`` or 3-vector as any sequence of floats (tuple, list, 1-D array) and
return tuples of Python floats: per-joint loops (the analytic IK, the limb step after
the latent solve) handle one rotation at a time, where numpy's per-call overhead costs
10-20x the arithmetic. The array functions take their single-rotation paths from them.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np
import pymotion.rotations.quat_np as _pm

Vec = tuple[float, float, float]
Quat = tuple[float, float, float, float]
#: What the one-rotation helpers below (and :func:`mul`, :func:`rotate`) take: a tuple,
#: a list or an array of floats.
Floats = Sequence[float] | np.ndarray
IDENTITY: Quat = (1.0, 0.0, 0.0, 0.0)

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
    return np.array(qmul(a.tolist(), b.tolist()))


def mul(q0: Floats, q1: Floats) -> np.ndarray:
    """Hamilton product ``q0 * q1``, ``(..., 4)``.

    Two single quaternions ``(4,)`` take a scalar path: at that size numpy's per-call
    overhead costs more than the arithmetic (IK multiplies many single rotations)."""
    if np.ndim(q0) == 1 and np.ndim(q1) == 1:
        return np.array(qmul(_floats(q0), _floats(q1)))
    q0, q1 = np.asarray(q0), np.asarray(q1)
    shape = q0.shape if q0.shape == q1.shape else np.broadcast_shapes(q0.shape, q1.shape)  # the common case first
    return (q0[..., :, None] * q1[..., None, :]).reshape(shape[:-1] + (16,)) @ _MUL


def rotate(q: np.ndarray, v: Floats) -> np.ndarray:
    """Rotate vectors ``v (..., 3)`` by unit quaternions ``q (..., 4)`` (one ``(4,)`` by
    one ``(3,)`` takes a scalar path, as in :func:`mul`)."""
    if np.ndim(q) == 1 and np.ndim(v) == 1:
        return np.array(qrotate(_floats(q), _floats(v)))
    return (to_matrix(q) @ np.asarray(v)[..., None])[..., 0]


def conjugate(q: np.ndarray) -> np.ndarray:
    """Inverse of a unit quaternion, ``(..., 4)``."""
    return q * _CONJ


def to_matrix(q: np.ndarray) -> np.ndarray:
    """Unit quaternions ``(..., 4)`` to rotation matrices ``(..., 3, 3)`` (the quadratic
    form ``R = q (0, v) q*``, :data:`MATRIX_TABLE`; it scales by ``|q|^2`` for non-unit
    input). The torch kit uses the same table."""
    q = np.asarray(q)
    return ((q[..., :, None] * q[..., None, :]).reshape(q.shape[:-1] + (16,)) @ _MAT).reshape(q.shape[:-1] + (3, 3))


def unit_to_matrix(q: np.ndarray) -> np.ndarray:
    """Rotation matrices ``(..., 3, 3)`` of quaternions ``q (..., 4)`` of any length
    (targets typed by a user or read from a tracker): normalised first, a zero quaternion
    taken as the identity."""
    q = np.asarray(q, dtype=np.float64)
    n = np.linalg.norm(q, axis=-1, keepdims=True)
    return to_matrix(np.where(n > 0.0, q / np.maximum(n, 1e-12), np.array(IDENTITY)))


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


def normalize(q: np.ndarray, eps: float = 1e-8) -> np.ndarray:
    """``q / |q|`` along the last axis (``eps`` keeps a zero quaternion finite)."""
    return q / np.maximum(np.linalg.norm(q, axis=-1, keepdims=True), eps)


def canonicalize(q: np.ndarray) -> np.ndarray:
    """The representative with ``w >= 0`` (q and -q are the same rotation)."""
    return np.where(q[..., :1] < 0, -q, q)


def identity(shape: tuple[int, ...] = ()) -> np.ndarray:
    """Identity rotations ``shape + (4,)``."""
    out = np.zeros(shape + (4,))
    out[..., 0] = 1.0
    return out


def from_axis_angle(axis: np.ndarray, angle: np.ndarray) -> np.ndarray:
    """Rotations of ``angle (...,)`` radians about unit ``axis (..., 3)``."""
    half = 0.5 * np.asarray(angle)
    return np.concatenate((np.cos(half)[..., None], np.sin(half)[..., None] * axis), axis=-1)


def angle(q0: np.ndarray, q1: np.ndarray) -> np.ndarray:
    """Geodesic angle (radians) between two rotations, ``(...,)``; in [0, pi]."""
    d = np.clip(np.abs((q0 * q1).sum(-1)), 0.0, 1.0)
    return 2.0 * np.arccos(d)


def mirror_x(q: np.ndarray) -> np.ndarray:
    """Conjugate a rotation by the reflection ``x -> -x`` (the left/right mirror)."""
    return q * np.array([1.0, 1.0, -1.0, -1.0])


# Batched conversions that upc-pymotion provides.


def from_euler(euler_rad: np.ndarray, order: np.ndarray) -> np.ndarray:
    """Euler angles (radians) ``(..., J, 3)`` with per-joint ``order (..., J, 3)`` of 'x'/'y'/'z'."""
    return _pm.from_euler(euler_rad, order=order)


def to_euler(q: np.ndarray, order: np.ndarray) -> np.ndarray:
    """Inverse of :func:`from_euler` (radians)."""
    return _pm.to_euler(q, order=order)


def from_to(v0: np.ndarray, v1: np.ndarray) -> np.ndarray:
    """Shortest rotations taking directions ``v0 (..., 3)`` onto ``v1 (..., 3)``."""
    return _pm.from_to(np.asarray(v0, dtype=float), np.asarray(v1, dtype=float))


def from_matrix(m: np.ndarray) -> np.ndarray:
    """Rotation matrices ``(..., 3, 3)`` to quaternions."""
    return _pm.from_matrix(m)


def unroll(q: np.ndarray, axis: int = 0) -> np.ndarray:
    """Flip signs along ``axis`` (time) so consecutive quaternions stay in one hemisphere."""
    return _pm.unroll(q, axis=axis)


def slerp(q0: np.ndarray, q1: np.ndarray, t: np.ndarray) -> np.ndarray:
    """Spherical interpolation, ``t`` broadcast against ``(...,)``."""
    return _pm.slerp(q0, q1, t)


# -- one rotation or vector: sequences of floats in, tuples of floats out --------------


def _floats(a: Sequence[float] | np.ndarray) -> Sequence[float]:
    return a.tolist() if isinstance(a, np.ndarray) else a


def vsub(a: Floats, b: Floats) -> Vec:
    """``a - b`` of two 3-vectors."""
    return (a[0] - b[0], a[1] - b[1], a[2] - b[2])


def vdot(a: Floats, b: Floats) -> float:
    """Dot product of two 3-vectors."""
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


def vcross(a: Floats, b: Floats) -> Vec:
    """Cross product ``a x b`` of two 3-vectors."""
    return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])


def vnorm(a: Floats) -> float:
    """Length of a 3-vector."""
    return math.sqrt(vdot(a, a))


def vscale(a: Floats, s: float) -> tuple[float, ...]:
    """``s * a`` for a vector or quaternion of any length."""
    return tuple(s * x for x in a)


def qnorm(q: Floats) -> float:
    """Length of a quaternion (any 4 numbers)."""
    return math.sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3])


def qmul(q0: Floats, q1: Floats) -> Quat:
    """Hamilton product ``q0 * q1``."""
    w0, x0, y0, z0 = q0
    w1, x1, y1, z1 = q1
    return (
        w0 * w1 - x0 * x1 - y0 * y1 - z0 * z1,
        w0 * x1 + x0 * w1 + y0 * z1 - z0 * y1,
        w0 * y1 - x0 * z1 + y0 * w1 + z0 * x1,
        w0 * z1 + x0 * y1 - y0 * x1 + z0 * w1,
    )


def qconj(q: Floats) -> Quat:
    """Conjugate: the inverse of a unit quaternion."""
    return (q[0], -q[1], -q[2], -q[3])


def qrotate(q: Floats, v: Floats) -> Vec:
    """The 3-vector ``v`` rotated by the unit quaternion ``q``."""
    w, x, y, z = q
    a, b, c = v
    tx, ty, tz = 2.0 * (y * c - z * b), 2.0 * (z * a - x * c), 2.0 * (x * b - y * a)
    return (a + w * tx + y * tz - z * ty, b + w * ty + z * tx - x * tz, c + w * tz + x * ty - y * tx)


def qaxis_angle(axis: Floats, angle: float) -> Quat:
    """Rotation of ``angle`` radians about the *unit* 3-vector ``axis``."""
    s = math.sin(angle / 2)
    return (math.cos(angle / 2), s * axis[0], s * axis[1], s * axis[2])


def qabout(axis: Floats, angle: float) -> Quat:
    """Rotation of ``angle`` radians about ``axis`` of any length; the identity when the
    axis or the angle is below 1e-12."""
    n = vnorm(axis)
    if n < 1e-12 or abs(angle) < 1e-12:
        return IDENTITY
    s = math.sin(angle / 2)
    return (math.cos(angle / 2), s * axis[0] / n, s * axis[1] / n, s * axis[2] / n)


def qbetween(u: Floats, v: Floats) -> Quat:
    """Smallest rotation taking the direction of ``u`` onto that of ``v`` (a half turn
    about an axis perpendicular to ``u`` when they are opposite; the identity when either
    is shorter than 1e-12)."""
    nu, nv = vnorm(u), vnorm(v)
    if nu < 1e-12 or nv < 1e-12:
        return IDENTITY
    u, v = vscale(u, 1.0 / nu), vscale(v, 1.0 / nv)
    c = vcross(u, v)
    q = (1.0 + vdot(u, v), *c)
    n = math.sqrt(q[0] * q[0] + vdot(c, c))
    if n < 1e-9:  # opposite: any perpendicular axis
        perp = vcross(u, (1.0, 0.0, 0.0) if abs(u[0]) < 0.9 else (0.0, 1.0, 0.0))
        return qaxis_angle(vscale(perp, 1.0 / vnorm(perp)), math.pi)
    return vscale(q, 1.0 / n)  # type: ignore[return-value]


def qpow(q: Floats, t: float) -> Quat:
    """``q`` scaled to ``t`` times its angle, the short way round."""
    q = tuple(q) if q[0] >= 0 else tuple(-x for x in q)
    return qabout(q[1:], t * 2.0 * math.acos(min(1.0, q[0])))


def qtwist(q: Floats, axis: Floats) -> Quat:
    """Twist part of ``q`` about ``axis`` (swing-twist decomposition ``q = swing * twist``);
    the identity when ``q`` has no twist component."""
    n = vnorm(axis)
    a = (axis[0] / n, axis[1] / n, axis[2] / n)
    along = vdot(q[1:], a)
    t = (q[0], along * a[0], along * a[1], along * a[2])
    m = qnorm(t)
    return tuple(x / m for x in t) if m > 1e-9 else IDENTITY  # type: ignore[return-value]


def qfrom_matrix(m: np.ndarray) -> Quat:
    """One orthonormal rotation matrix ``(3, 3)`` as a unit quaternion (the numerically
    safest of the trace and diagonal branches)."""
    tr = m[0, 0] + m[1, 1] + m[2, 2]
    if tr > 0:
        s = 2.0 * math.sqrt(1.0 + tr)
        q = [0.25 * s, (m[2, 1] - m[1, 2]) / s, (m[0, 2] - m[2, 0]) / s, (m[1, 0] - m[0, 1]) / s]
    else:
        i = int(np.argmax(np.diag(m)))
        j, k = (i + 1) % 3, (i + 2) % 3
        s = 2.0 * math.sqrt(max(1e-12, 1.0 + m[i, i] - m[j, j] - m[k, k]))
        q = [(m[k, j] - m[j, k]) / s, 0.0, 0.0, 0.0]
        q[1 + i] = 0.25 * s
        q[1 + j] = (m[j, i] + m[i, j]) / s
        q[1 + k] = (m[k, i] + m[i, k]) / s
    n = qnorm(q)
    return (float(q[0] / n), float(q[1] / n), float(q[2] / n), float(q[3] / n))


def _frame(u: Floats, w: Floats) -> np.ndarray:
    """Orthonormal frame (columns) with x along ``u`` and y in the plane of ``u`` and ``w``."""
    n = vnorm(u)
    x = (u[0] / n, u[1] / n, u[2] / n)
    along = vdot(w, x)
    y = (w[0] - along * x[0], w[1] - along * x[1], w[2] - along * x[2])
    if vnorm(y) < 1e-9:
        y = vcross(x, (0.0, 0.0, 1.0) if abs(x[2]) < 0.9 else (1.0, 0.0, 0.0))
    m = vnorm(y)
    y = (y[0] / m, y[1] / m, y[2] / m)
    return np.array([x, y, vcross(x, y)]).T


def qfrom_bases(u0: Floats, w0: Floats, u1: Floats, w1: Floats) -> Quat:
    """Rotation taking direction ``u0`` onto ``u1`` and the plane of (``u0``, ``w0``) onto
    that of (``u1``, ``w1``)."""
    return qfrom_matrix(_frame(u1, w1) @ _frame(u0, w0).T)


#: The product tensors of :func:`mul` and :func:`to_matrix` (built from :func:`qmul`).
_MUL, _MAT = _product_tensors()
#: ``(16, 9)``: coefficient of ``q_j q_k`` (row ``4 j + k``) in ``R(q)[r, c]`` (column ``3 r + c``).
MATRIX_TABLE = _MAT
#: ``(16, 4)``: coefficient of ``a_j b_k`` (row ``4 j + k``) in the product ``a * b``.
MUL_TABLE = _MUL
