"""The torch quaternion kit, batched, which also takes numpy arrays.

Quaternions are ``(..., 4)`` arrays in ``(w, x, y, z)`` order. Torch tensors are handled
here (with upc-pymotion's ``quat_torch`` for matrix to quaternion); numpy arrays go to
the numpy kit, :mod:`engine.kinematics.quat_np`, so each operation has one numpy and one
torch implementation. Code that only ever holds numpy arrays can import the numpy kit
directly and skip the dispatch.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, TypeVar, overload

import numpy as np

from engine.kinematics import quat_np as _np
from engine.kinematics.backend import is_tensor

if TYPE_CHECKING:  # imported by whoever made a tensor; numpy callers never load torch
    import torch

Array = TypeVar("Array", np.ndarray, "torch.Tensor")

#: Operations only numpy arrays take: the numpy kit's own functions.
from_euler = _np.from_euler
to_euler = _np.to_euler
from_to = _np.from_to
unroll = _np.unroll
slerp = _np.slerp


def mul(q0: Array, q1: Array) -> Array:
    """Hamilton product ``q0 * q1``; shapes broadcast, ``(..., 4)``."""
    if is_tensor(q0):
        import torch  # loaded: q0 is a tensor

        w0, x0, y0, z0 = q0.unbind(-1)
        w1, x1, y1, z1 = q1.unbind(-1)
        return torch.stack(
            (
                w0 * w1 - x0 * x1 - y0 * y1 - z0 * z1,
                w0 * x1 + x0 * w1 + y0 * z1 - z0 * y1,
                w0 * y1 - x0 * z1 + y0 * w1 + z0 * x1,
                w0 * z1 + x0 * y1 - y0 * x1 + z0 * w1,
            ),
            dim=-1,
        )
    return _np.mul(q0, q1)


def rotate(q: Array, v: Array) -> Array:
    """Rotate vectors ``v (..., 3)`` by quaternions ``q (..., 4)``."""
    w = q[..., :1]
    u = q[..., 1:]
    if is_tensor(q):
        import torch  # loaded: q is a tensor

        shape = torch.broadcast_shapes(u.shape, v.shape)
        u, v, w = u.expand(shape), v.expand(shape), w.expand(shape[:-1] + (1,))
        t = 2.0 * torch.linalg.cross(u, v, dim=-1)
        return v + w * t + torch.linalg.cross(u, t, dim=-1)
    return _np.rotate(q, v)


def conjugate(q: Array) -> Array:
    """Inverse of a unit quaternion."""
    if is_tensor(q):
        import torch  # loaded: q is a tensor

        return q * torch.tensor([1.0, -1.0, -1.0, -1.0], dtype=q.dtype, device=q.device)
    return _np.conjugate(q)


inverse = conjugate


def normalize(q: Array, eps: float = 1e-8) -> Array:
    if is_tensor(q):
        import torch  # loaded: q is a tensor

        return q / torch.linalg.vector_norm(q, dim=-1, keepdim=True).clamp_min(eps)
    return _np.normalize(q, eps)


def canonicalize(q: Array) -> Array:
    """Pick the representative with ``w >= 0`` (q and -q are the same rotation)."""
    if is_tensor(q):
        import torch  # loaded: q is a tensor

        return torch.where(q[..., :1] < 0, -q, q)
    return _np.canonicalize(q)


@overload
def identity(shape: tuple[int, ...] = (), *, like: torch.Tensor) -> torch.Tensor: ...
@overload
def identity(shape: tuple[int, ...] = (), like: np.ndarray | None = None) -> np.ndarray: ...
def identity(shape: tuple[int, ...] = (), like: np.ndarray | torch.Tensor | None = None) -> np.ndarray | torch.Tensor:
    """Identity quaternions ``shape + (4,)``: a tensor of ``like``'s dtype and device when
    ``like`` is one, else a numpy array."""
    if is_tensor(like):
        import torch  # loaded: like is a tensor

        out = torch.zeros(shape + (4,), dtype=like.dtype, device=like.device)
        out[..., 0] = 1.0
        return out
    return _np.identity(shape)


def from_axis_angle(axis: Array, angle: Array) -> Array:
    """Rotation of ``angle (...,)`` radians about unit ``axis (..., 3)``."""
    if is_tensor(axis):
        import torch  # loaded: axis is a tensor

        half = 0.5 * angle
        return torch.cat((torch.cos(half)[..., None], torch.sin(half)[..., None] * axis), dim=-1)
    return _np.from_axis_angle(axis, angle)


def from_matrix(m: Array) -> Array:
    """Rotation matrices ``(..., 3, 3)`` to quaternions."""
    if not is_tensor(m):
        return _np.from_matrix(m)
    import pymotion.rotations.quat_torch as _qt  # imports torch, which a tensor argument has loaded

    return _qt.from_matrix(m)


def to_matrix(q: Array) -> Array:
    """Unit quaternions ``(..., 4)`` (w, x, y, z) to rotation matrices ``(..., 3, 3)``:
    the numpy kit's quadratic form (:func:`engine.kinematics.quat_np.to_matrix`) for both
    array kinds, its coefficient table copied once per dtype and device for tensors."""
    if not is_tensor(q):
        return _np.to_matrix(q)
    import torch  # loaded: q is a tensor

    key = (q.dtype, q.device)
    table = _MATRIX_TABLES.get(key)
    if table is None:
        table = _MATRIX_TABLES[key] = torch.as_tensor(_np.MATRIX_TABLE, dtype=q.dtype, device=q.device)
    return ((q[..., :, None] * q[..., None, :]).reshape(q.shape[:-1] + (16,)) @ table).reshape(q.shape[:-1] + (3, 3))


#: :data:`engine.kinematics.quat_np.MATRIX_TABLE` as tensors, by (dtype, device).
_MATRIX_TABLES: dict = {}


def angle(q0: Array, q1: Array) -> Array:
    """Geodesic angle (radians) between two rotations, ``(...,)``; in [0, pi]."""
    if is_tensor(q0):
        import torch  # loaded: q0 is a tensor

        d = (q0 * q1).sum(-1).abs().clamp(max=1.0)
        return 2.0 * torch.arccos(d)
    return _np.angle(q0, q1)


def heading(q: Array) -> Array:
    """Yaw-only part of a rotation: rotation about +Z that turns the rest forward (-Y)
    onto the horizontal projection of ``q``'s forward. Shape ``(..., 4)``."""
    if not is_tensor(q):
        return _np.heading(q)
    import torch  # loaded: q is a tensor

    f = torch.tensor([0.0, -1.0, 0.0], dtype=q.dtype, device=q.device)
    fw = rotate(q, f.expand(q.shape[:-1] + (3,)))
    half = 0.5 * torch.atan2(fw[..., 0], -fw[..., 1])
    z = torch.zeros_like(half)
    return torch.stack((torch.cos(half), z, z, torch.sin(half)), dim=-1)


def mirror_x(q: Array) -> Array:
    """Conjugate a rotation by the reflection ``x -> -x`` (the left/right mirror)."""
    if is_tensor(q):
        import torch  # loaded: q is a tensor

        return q * torch.tensor([1.0, 1.0, -1.0, -1.0], dtype=q.dtype, device=q.device)
    return _np.mirror_x(q)
