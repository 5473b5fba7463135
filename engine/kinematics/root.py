"""The root-integration rule of the pose representation, in one place.

A pose stores the root's rotation and displacement relative to the previous frame's
*heading frame* ``H`` (the yaw-only part of the previous root rotation, see
:func:`engine.kinematics.quaternion.heading`): ``R(t) = H * rot0`` and
``p(t) = p(t-1) + H * disp``. :func:`integrate_root` applies it, :func:`root_increment`
inverts it. Both work on numpy arrays and torch tensors, batched over leading axes.
"""

from __future__ import annotations

from engine.kinematics import quaternion as Q


def integrate_root(prev_rot, prev_pos, rot0, disp):
    """World root rotation and position of a frame from its relative root pose.

    Parameters
    ----------
    prev_rot : (..., 4)
        World root rotation of the previous frame.
    prev_pos : (..., 3)
        World root position of the previous frame, metres.
    rot0 : (..., 4)
        Root rotation in the previous heading frame (slot 0 of a pose).
    disp : (..., 3)
        Root displacement in the previous heading frame, metres.

    Returns
    -------
    rotation : (..., 4)
    position : (..., 3)
        Metres.
    """
    h = Q.heading(prev_rot)
    return Q.mul(h, rot0), prev_pos + Q.rotate(h, disp)


def root_increment(prev_rot, prev_pos, rot, pos):
    """Inverse of :func:`integrate_root`: ``(rot0 (..., 4), disp (..., 3))`` of a frame
    whose world root is ``rot``, ``pos`` after a frame with ``prev_rot``, ``prev_pos``."""
    h_inv = Q.conjugate(Q.heading(prev_rot))
    return Q.mul(h_inv, rot), Q.rotate(h_inv, pos - prev_pos)


def root_displacement(prev_rot, prev_pos, pos):
    """The displacement half of :func:`root_increment` alone, ``(..., 3)`` metres (the same
    operations, so the same rounding), for callers that do not need the rotation."""
    return Q.rotate(Q.conjugate(Q.heading(prev_rot)), pos - prev_pos)
