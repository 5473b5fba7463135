"""The DragPoser pose representation and the encoder's root-space dual quaternions.

DragPoser (Ponton et al. 2024, sec. 4.1) describes a pose ``x`` by the rotations of
the joints in a frame attached to the character plus, for the root, the rotational
increment and displacement with respect to the previous pose. We make that precise:

* **Pose** ``(rot, disp)``: ``rot (..., J, 4)`` holds the **local** rotation of every
  joint 1..J-1 and, in slot 0, the root's world rotation expressed in the previous
  frame's *heading frame* (its yaw-only part, see :func:`Q.heading`):
  ``rot[0] = H(t-1)^-1 R_root(t)``. This keeps the root's tilt against gravity (which
  root-relative rotations would lose) and its yaw increment. ``disp (..., 3)`` is the
  root displacement ``H(t-1)^-1 (p(t) - p(t-1))`` in metres. At t = 0 the previous
  frame is the frame itself.
* Quaternions are given with ``w >= 0`` (rotations of one joint rarely pass 180 degrees,
  so this sign choice is continuous in practice).
* **Encoder input** ``(..., J, 8)``: slot 0 is the dual quaternion of ``(rot[0], disp)``;
  slot j is the dual quaternion of joint j's rotation and position *relative to the
  root joint* (root-space), which tells the encoder the skeleton's dimensions.
"""

from __future__ import annotations

import numpy as np
import pymotion.rotations.dual_quat_np as _dq_np
import pymotion.rotations.dual_quat_torch as _dq_t
import torch

from engine import skeleton as sk
from engine.kinematics import quaternion as Q
from engine.kinematics.fk import fk, fk_matrices
from engine.kinematics.root import place_root, root_increment


def _cat(xs, dim):
    return torch.cat(xs, dim=dim) if isinstance(xs[0], torch.Tensor) else np.concatenate(xs, axis=dim)


def pose_from_motion(local_rot, root_pos):
    """Pose representation of a motion.

    Parameters
    ----------
    local_rot : array (F, J, 4)
        Local rotations; row 0 is the root's world rotation.
    root_pos : array (F, 3)
        Root world positions, metres.

    Returns
    -------
    rot : array (F, J, 4)
        ``local_rot`` with slot 0 replaced by the root rotation in the previous heading frame.
    disp : array (F, 3)
        Root displacement in the previous heading frame, metres per frame.
    """
    root = local_rot[:, 0]
    prev_root = _cat([root[:1], root[:-1]], 0)
    prev_pos = _cat([root_pos[:1], root_pos[:-1]], 0)
    rot0, disp = root_increment(prev_root, prev_pos, root, root_pos)
    rot = local_rot.clone() if isinstance(local_rot, torch.Tensor) else local_rot.copy()
    rot[:, 0] = rot0
    return Q.canonicalize(rot), disp


def motion_from_pose(rot, disp, start_root_rot=None, start_pos=None):
    """Integrate a pose sequence back to world motion (inverse of :func:`pose_from_motion`).

    Parameters
    ----------
    rot : array (F, J, 4), disp : array (F, 3)
        Pose sequence.
    start_root_rot : array (4,), optional
        World root rotation of the frame *before* the first one (its heading is used).
        Default: the first frame is its own predecessor.
    start_pos : array (3,), optional
        World root position of the frame before the first one. Default: origin.
    """
    is_t = isinstance(rot, torch.Tensor)
    # Without a predecessor the first frame is its own: rot[0, 0] then has zero yaw relative
    # to its own heading, so the clip is anchored at zero yaw at the origin.
    prev_rot = start_root_rot if start_root_rot is not None else Q.identity((), like=rot if is_t else None)
    prev_pos = start_pos if start_pos is not None else (torch.zeros(3, dtype=rot.dtype) if is_t else np.zeros(3))
    roots, poss = [], []
    for t in range(rot.shape[0]):
        prev_rot, prev_pos = place_root(Q.heading(prev_rot), rot[t, 0], prev_pos, disp[t])
        roots.append(prev_rot)
        poss.append(prev_pos)
    if is_t:
        return torch.cat((torch.stack(roots)[:, None], rot[:, 1:]), dim=1), torch.stack(poss)
    local = rot.copy()
    local[:, 0] = np.stack(roots)
    return local, np.stack(poss)


def _root_frame(rot):
    """``rot`` with the identity in slot 0, and a zero root position."""
    zero: np.ndarray | torch.Tensor
    if isinstance(rot, torch.Tensor):
        ident = Q.identity(rot.shape[:-2], like=rot)[..., None, :]
        r = torch.cat((ident, rot[..., 1:, :]), dim=-2)
        zero = torch.zeros(rot.shape[:-2] + (3,), dtype=rot.dtype, device=rot.device)
    else:
        r = rot.copy()
        r[..., 0, :] = Q.identity(rot.shape[:-2])
        zero = np.zeros(rot.shape[:-2] + (3,))
    return r, zero


def root_space_fk(rot, offsets):
    """Joint positions and rotations relative to the root joint, ``(..., J, 3)`` and ``(..., J, 4)``.

    Slot 0 of ``rot`` is ignored (the root is the frame of reference)."""
    r, zero = _root_frame(rot)
    return fk(r, zero, offsets)


def root_space_positions(rot, offsets):
    """The positions of :func:`root_space_fk` (the same values), without composing the
    world quaternions (what a position loss reads): ``(..., J, 3)``."""
    r, zero = _root_frame(rot)
    return fk_matrices(Q.to_matrix(r), zero, offsets)[0]


def encoder_input(rot, disp, offsets):
    """Root-space dual quaternions ``(..., J, 8)`` fed to the pose encoder (see module doc).

    Each dual quaternion is given the sign whose real part has ``w >= 0`` (``q`` and
    ``-q`` are the same transform), so the network never sees both."""
    return root_space_features(rot, disp, offsets)[1]


def root_space_features(rot, disp, offsets):
    """Root-space joint positions ``(..., J, 3)`` and the encoder input ``(..., J, 8)``
    of a pose, from one FK pass (what a training batch needs of every augmented pose)."""
    pos, grot = root_space_fk(rot, offsets)
    return pos, _dual_quaternions(rot, disp, pos, grot)


def _dual_quaternions(rot, disp, pos, grot):
    if isinstance(rot, torch.Tensor):
        grot = torch.cat((rot[..., :1, :], grot[..., 1:, :]), dim=-2)
        pos = torch.cat((disp[..., None, :], pos[..., 1:, :]), dim=-2)
        return _dq_t.from_rotation_translation(Q.canonicalize(grot), pos)
    grot = np.concatenate((rot[..., :1, :], grot[..., 1:, :]), axis=-2)
    pos = np.concatenate((disp[..., None, :], pos[..., 1:, :]), axis=-2)
    return _dq_np.from_rotation_translation(Q.canonicalize(grot), pos)


def heights(local_rot, root_pos, offsets, joints=sk.HEIGHT_JOINTS):
    """Heights above the floor (z) of the given joints, ``(..., len(joints))`` metres."""
    pos, _ = fk(local_rot, root_pos, offsets)
    idx = [sk.JOINT_INDEX[j] for j in joints]
    return pos[..., idx, 2]


def heights_from_root_space(root_rot, root_pos, positions, joints=sk.HEIGHT_JOINTS):
    """:func:`heights` from the root-space positions of :func:`root_space_fk` of the same
    pose (``(..., J, 3)``), the root's world rotation ``(..., 4)`` and position
    ``(..., 3)``: the same values without a second FK pass (loading a training split)."""
    idx = [sk.JOINT_INDEX[j] for j in joints]
    return root_pos[..., None, 2] + Q.rotate(root_rot[..., None, :], positions[..., idx, :])[..., 2]


def mirror_motion(local_rot, root_pos, offsets):
    """Left/right mirror (reflection x -> -x) of a canonical motion.

    Returns ``(local_rot, root_pos, offsets)`` of the mirrored clip."""
    idx = list(sk.MIRROR_INDEX)
    rot = Q.mirror_x(local_rot[..., idx, :])
    pos = root_pos * np.array([-1.0, 1.0, 1.0])
    off = offsets[idx] * np.array([-1.0, 1.0, 1.0])
    return rot, pos, off
