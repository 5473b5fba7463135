"""Explicit coordinate conversions between tracking systems and the project's frame.

The project's frame (``docs/skeleton.md``): metres, right-handed, **Z up**, the rest pose
faces **-Y** and the character's left is **+X**. Tracking systems use other axes:

============ ============= ===== ============ ============== ===========================
convention   handedness    up    forward      character left maps project (x, y, z) to
============ ============= ===== ============ ============== ===========================
``project``  right         +Z    -Y           +X             ( x,  y,  z)
``unity``    left          +Y    +Z           -X             (-x,  z, -y)
``openxr``   right         +Y    -Z           -X             (-x,  z,  y)
============ ============= ===== ============ ============== ===========================

``unity`` is what VMC (the Virtual Motion Capture protocol) sends: Unity world space,
left-handed, Y up, metres, quaternions as ``(x, y, z, w)``. ``openxr`` is OpenXR's stage
or local space (also SteamVR's): right-handed, Y up, -Z forward.

A position converts by the axis matrix ``M`` (``v_c = M v_p``). A rotation ``R``
converts by conjugation, ``R_c = M R M^T``, which keeps what a tracker "means": the
same physical axis of the device maps to the same physical direction. For a proper
``M`` (det +1) the quaternion's vector part is rotated by ``M``; for a reflection
(det -1, a handedness change) it is rotated by ``-M``, because ``M R M^T = (-M) R (-M)^T``
and ``-M`` is a proper rotation in 3D. So, from project to Unity,
``(w, x, y, z) -> (w, x, -z, y)`` and from project to OpenXR
``(w, x, y, z) -> (w, -x, z, y)``; the tests check these against the matrices.
"""

from __future__ import annotations

import numpy as np

from engine.errors import UserError

#: Axis matrices M with ``v_convention = M @ v_project``.
AXES: dict[str, np.ndarray] = {
    "project": np.eye(3),
    "unity": np.array([[-1.0, 0.0, 0.0], [0.0, 0.0, 1.0], [0.0, -1.0, 0.0]]),
    "openxr": np.array([[-1.0, 0.0, 0.0], [0.0, 0.0, 1.0], [0.0, 1.0, 0.0]]),
}

CONVENTIONS: tuple[str, ...] = tuple(AXES)


def _axes(convention: str) -> np.ndarray:
    try:
        return AXES[convention]
    except KeyError:
        raise UserError(f"unknown coordinate convention {convention!r}; known: {', '.join(CONVENTIONS)}") from None


def _vector_map(convention: str) -> np.ndarray:
    """The proper rotation that maps a quaternion's vector part (M or -M)."""
    m = _axes(convention)
    return m * np.sign(np.linalg.det(m))


def to_project(position: np.ndarray, quat_wxyz: np.ndarray, convention: str) -> tuple[np.ndarray, np.ndarray]:
    """Convert a pose from ``convention`` into the project's frame.

    Parameters
    ----------
    position : ndarray (..., 3)
        Metres, in the source convention.
    quat_wxyz : ndarray (..., 4)
        Orientation (w, x, y, z) in the source convention.
    convention : str
        One of :data:`CONVENTIONS`.

    Returns
    -------
    position : ndarray (..., 3)
    quat_wxyz : ndarray (..., 4)
    """
    m = _axes(convention)
    v = _vector_map(convention)
    pos = np.asarray(position, float) @ m  # M^T p, row-vector form
    q = np.asarray(quat_wxyz, float)
    return pos, np.concatenate([q[..., :1], q[..., 1:] @ v], axis=-1)


def from_project(position: np.ndarray, quat_wxyz: np.ndarray, convention: str) -> tuple[np.ndarray, np.ndarray]:
    """Convert a pose from the project's frame into ``convention`` (inverse of
    :func:`to_project`); shapes as there."""
    m = _axes(convention)
    v = _vector_map(convention)
    pos = np.asarray(position, float) @ m.T
    q = np.asarray(quat_wxyz, float)
    return pos, np.concatenate([q[..., :1], q[..., 1:] @ v.T], axis=-1)


def xyzw_to_wxyz(q: np.ndarray) -> np.ndarray:
    """Reorder quaternions ``(..., x, y, z, w)`` (Unity, VMC, OpenXR) to ``(w, x, y, z)``."""
    q = np.asarray(q, float)
    return np.concatenate([q[..., 3:], q[..., :3]], axis=-1)


def wxyz_to_xyzw(q: np.ndarray) -> np.ndarray:
    """Reorder quaternions ``(..., w, x, y, z)`` to ``(x, y, z, w)``."""
    q = np.asarray(q, float)
    return np.concatenate([q[..., 1:], q[..., :1]], axis=-1)
