"""Forward kinematics for the canonical skeleton (pure, batched; numpy or torch).

The loop over joints builds lists instead of writing into preallocated tensors, so
autograd through FK (the optimizer's hot path) records no in-place copies.
"""

from __future__ import annotations

import numpy as np
import torch

from engine import skeleton as sk
from engine.kinematics import quaternion as Q


def fk(local_rot, root_pos, offsets, parents=sk.PARENTS):
    """World joint positions and rotations from local rotations.

    Parameters
    ----------
    local_rot : array (..., J, 4)
        Local joint rotations (row 0 is the root's world rotation), unit quaternions.
    root_pos : array (..., 3)
        World position of the root, metres.
    offsets : array (J, 3) or (..., J, 3)
        Bone offsets from each joint's parent, metres.
    parents : sequence of int, length J
        Parent index per joint, -1 (or the joint itself) for the root.

    Returns
    -------
    positions : array (..., J, 3)
        World joint positions, metres.
    rotations : array (..., J, 4)
        World joint rotations.
    """
    is_t = isinstance(local_rot, torch.Tensor)
    stack = (lambda xs: torch.stack(xs, dim=-2)) if is_t else (lambda xs: np.stack(xs, axis=-2))
    if is_t and not isinstance(offsets, torch.Tensor):
        offsets = torch.as_tensor(offsets, dtype=local_rot.dtype, device=local_rot.device)
    n = local_rot.shape[-2]
    g_rot = [local_rot[..., 0, :]]
    g_pos = [root_pos]
    for j in range(1, n):
        p = parents[j]
        g_rot.append(Q.mul(g_rot[p], local_rot[..., j, :]))
        g_pos.append(g_pos[p] + Q.rotate(g_rot[p], offsets[..., j, :]))
    return stack(g_pos), stack(g_rot)


def local_from_global(global_rot, parents=sk.PARENTS):
    """Local rotations ``(..., J, 4)`` from world rotations ``(..., J, 4)``."""
    is_t = isinstance(global_rot, torch.Tensor)
    out = [global_rot[..., 0, :]]
    for j in range(1, global_rot.shape[-2]):
        out.append(Q.mul(Q.conjugate(global_rot[..., parents[j], :]), global_rot[..., j, :]))
    return torch.stack(out, dim=-2) if is_t else np.stack(out, axis=-2)
