"""The root rule of the pose representation, in one place.

A pose stores the root's rotation and displacement relative to the previous frame's
*heading frame* ``H`` (the yaw-only part of the previous root rotation, see
:func:`engine.kinematics.quaternion.heading`): ``R(t) = H * rot0`` and
``p(t) = p(t-1) + H * disp``. :func:`place_root` applies it (and lets a hip tracker's
rotation or position take precedence), :func:`root_increment` inverts it, and
:func:`anchor_body` places a body by one joint instead (the head without a hip tracker). Both work on
numpy arrays and torch tensors, batched over leading axes.
"""

from __future__ import annotations

import numpy as np

from engine.kinematics import quaternion as Q
from engine.kinematics.backend import torch_of


def place_root(heading, rot0, prev_pos=None, disp=None, *, rotation=None, position=None):
    """World root rotation and position of a frame from its relative root pose.

    The rotations are all unit quaternions ``(..., 4)`` or all rotation matrices
    ``(..., 3, 3)``: the solver's numpy chain composes matrices (its FK reads them), the
    autograd reference, the clip features and the authoring previews quaternions.

    Parameters
    ----------
    heading : (..., 4) or (..., 3, 3)
        Heading ``H`` of the previous frame's world root rotation
        (:func:`~engine.kinematics.quaternion.heading`).
    rot0 : (..., 4) or (..., 3, 3)
        Root rotation in the previous heading frame (slot 0 of a pose).
    prev_pos : (..., 3), optional
        World root position of the previous frame, metres.
    disp : (..., 3), optional
        Root displacement in the previous heading frame, metres; None: the position is
        not wanted (None is returned for it unless ``position`` is given).
    rotation : (..., 4) or (..., 3, 3), optional
        A 6-DoF hip tracker's world rotation: the root's, instead of ``H * rot0``.
    position : (..., 3), optional
        A hip tracker's world position: the root's, instead of ``prev_pos + H * disp``.

    Returns
    -------
    rotation : (..., 4) or (..., 3, 3)
    position : (..., 3) or None
        Metres.
    """
    matrices = rot0.shape[-1] == 3
    if rotation is None:
        rotation = heading @ rot0 if matrices else Q.mul(heading, rot0)
    if position is None and disp is not None:
        if matrices:
            kit = torch_of(heading)
            einsum = kit.einsum if kit is not None else np.einsum
            position = prev_pos + einsum("...ij,...j->...i", heading, disp)
        else:
            position = prev_pos + Q.rotate(heading, disp)
    return rotation, position


def anchor_body(positions, joint, target):
    """``positions (..., J, 3)`` translated so that row ``joint`` lands on ``target (..., 3)``
    (metres): without a hip tracker, the head's tracker places the body and the decoded
    torso decides how far below it the hips are."""
    return positions + (target - positions[..., joint, :])[..., None, :]


def root_increment(prev_rot, prev_pos, rot, pos):
    """Inverse of :func:`place_root` (no tracker): ``(rot0 (..., 4), disp (..., 3))`` of a frame
    whose world root is ``rot``, ``pos`` after a frame with ``prev_rot``, ``prev_pos``."""
    h_inv = Q.conjugate(Q.heading(prev_rot))
    return Q.mul(h_inv, rot), Q.rotate(h_inv, pos - prev_pos)


def root_displacement(prev_rot, prev_pos, pos):
    """The displacement half of :func:`root_increment` alone, ``(..., 3)`` metres (the same
    operations, so the same rounding), for callers that do not need the rotation."""
    return Q.rotate(Q.conjugate(Q.heading(prev_rot)), pos - prev_pos)
