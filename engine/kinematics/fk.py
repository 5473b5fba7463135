"""Forward kinematics: the one implementation, level-ordered and batched (numpy or torch).

The skeleton is processed by depth: all joints at the same distance from the root are
placed at once (7 levels for the 22-joint skeleton instead of 21 joints), so the work
per call, and the autograd graph through it, stays small. Levels are built by
concatenation rather than by writing into a preallocated array, so autograd records no
in-place copies. Offsets are an argument (per clip, or per frame), never a global.
:func:`fk`, :func:`fk_positions` and :func:`fk_matrices` are that one pass
(:func:`_forward`); :func:`fk_joints` places a few joints of one pose in scalar
arithmetic for IK, which asks for them many times per frame (tested equal to :func:`fk`).
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache

import numpy as np

from engine import skeleton as sk
from engine.kinematics import quat_np as QN
from engine.kinematics import quaternion as Q
from engine.kinematics.backend import torch_of


@dataclass(frozen=True)
class Levels:
    """Joints grouped by depth, with the indices a level-ordered pass needs.

    Attributes
    ----------
    joints : tuple of ndarray
        ``joints[d]``: indices of the joints at depth ``d + 1``.
    parent_rows : tuple of ndarray
        Per level, the row of each joint's parent in level-ordered storage
        (root first, then level 1, level 2, ...).
    unorder : ndarray (J,)
        Row of every joint in level-ordered storage (gather back to joint order).
    order : ndarray (J,)
        Joint of every row (root, then level 1, 2, ...).
    prow : ndarray (J,)
        Row of every row's parent (the root: itself).
    chain : ndarray (J, J - 1)
        1 where the bone into row ``b + 1`` lies on the path from the root to row ``r``: a
        joint's position is the root's plus the world bone vectors on its path.
    parent_slices : tuple of (slice or None)
        Per level, its parents' rows as a slice when they are consecutive rows (one row
        per joint) or one row for all (broadcast): a view instead of a gather. None: a
        gather of :attr:`parent_rows`.
    level_parent_rows : tuple of ndarray
        Per level, the row of each joint's parent within the level above (the root's
        level: row 0).
    """

    joints: tuple[np.ndarray, ...]
    parent_rows: tuple[np.ndarray, ...]
    unorder: np.ndarray
    order: np.ndarray
    prow: np.ndarray
    chain: np.ndarray
    parent_slices: tuple[slice | None, ...] = ()
    level_parent_rows: tuple[np.ndarray, ...] = ()


@lru_cache(maxsize=32)
def levels(parents: tuple[int, ...]) -> Levels:
    """Depth levels of a skeleton given by ``parents`` (root first; -1 or itself for the
    root; every parent listed before its children, as in BVH)."""
    depth = [0] * len(parents)
    for j in range(1, len(parents)):
        p = parents[j]
        if not 0 <= p < j:
            raise ValueError(f"joint {j}: parent {p} must come before it")
        depth[j] = depth[p] + 1
    lv = [[j for j in range(len(parents)) if depth[j] == d] for d in range(1, max(depth, default=0) + 1)]
    order = [0] + [j for level in lv for j in level]
    row = {j: i for i, j in enumerate(order)}
    prow = np.array([0] + [row[parents[j]] for j in order[1:]], dtype=np.intp)
    chain = np.zeros((len(order), max(len(order) - 1, 0)))
    for r in range(1, len(order)):
        a = r
        while a != 0:
            chain[r, a - 1] = 1.0
            a = prow[a]
    parent_rows = tuple(np.array([row[parents[j]] for j in level]) for level in lv)
    return Levels(
        tuple(np.array(level) for level in lv),
        parent_rows,
        np.array([row[j] for j in range(len(parents))]),
        np.array(order, dtype=np.intp),
        prow,
        chain,
        tuple(_as_slice(rows) for rows in parent_rows),
        tuple(rows - first for rows, first in zip(parent_rows, np.cumsum([0, 1] + [len(x) for x in lv])[:-1])),
    )


def _as_slice(rows: np.ndarray) -> slice | None:
    """``rows`` as a slice of level-ordered storage: consecutive rows, or one row that a
    product broadcasts over the level; None when neither."""
    first = int(rows[0])
    if (rows == first).all():
        return slice(first, first + 1)
    if (np.diff(rows) == 1).all():
        return slice(first, first + len(rows))
    return None


def ancestors(parents, j: int) -> list[int]:
    """``j``, its parent, and so on up to the root (whose parent is -1 or itself)."""
    out = [int(j)]
    while 0 <= parents[out[-1]] != out[-1]:
        out.append(int(parents[out[-1]]))
    return out


def children(parents, j: int) -> list[int]:
    """The joints whose parent is ``j``, in order."""
    return [k for k, p in enumerate(parents) if p == j and k != j]


def _ops(x):
    torch = torch_of(x)
    if torch is not None:
        return (
            lambda a, i, d: a.index_select(d, torch.as_tensor(i, device=a.device)),
            lambda xs, d: torch.cat(xs, dim=d),
        )
    return (lambda a, i, d: np.take(a, i, axis=d)), (lambda xs, d: np.concatenate(xs, axis=d))


def _offsets_like(offsets, like):
    torch = torch_of(like)
    if torch is not None and not isinstance(offsets, torch.Tensor):
        return torch.as_tensor(np.asarray(offsets), dtype=like.dtype, device=like.device)
    return offsets


def fk(local_rot, root_pos, offsets, parents=sk.PARENTS):
    """World joint positions and rotations from local rotations (quaternions).

    Parameters
    ----------
    local_rot : array or Tensor (..., J, 4)
        Local joint rotations (row 0 is the root's world rotation), unit quaternions.
    root_pos : array or Tensor (..., 3)
        World position of the root, metres.
    offsets : array (J, 3) or (..., J, 3)
        Bone offsets from each joint's parent, metres (per clip: its true proportions).
    parents : sequence of int, length J
        Parent index per joint, -1 (or the joint itself) for the root.

    Returns
    -------
    positions : (..., J, 3)
        World joint positions, metres.
    rotations : (..., J, 4)
        World joint rotations.
    """
    if torch_of(local_rot) is None:
        local_rot, root_pos, offsets = np.asarray(local_rot), np.asarray(root_pos), np.asarray(offsets)
    pos, _, quats = _forward(Q.to_matrix(local_rot), root_pos, offsets, parents, local_rot)
    return pos, quats


def fk_positions(local_rot: np.ndarray, root_pos: np.ndarray, offsets: np.ndarray, parents=sk.PARENTS) -> np.ndarray:
    """The positions of :func:`fk` (the same values, bit for bit), without composing the
    world quaternions: ``(..., J, 3)``, metres."""
    local_rot = np.asarray(local_rot)
    return _forward(Q.to_matrix(local_rot), np.asarray(root_pos), np.asarray(offsets), parents)[0]


def fk_joints(
    local_rot: np.ndarray, root_pos: np.ndarray, offsets: np.ndarray, joints, parents=sk.PARENTS
) -> tuple[np.ndarray, np.ndarray]:
    """World position and rotation of a few joints of one pose: only their ancestors are
    placed (scalar arithmetic), which is what IK asks for many times per frame.

    Parameters
    ----------
    local_rot : array (J, 4)
        Local rotations of one pose (row 0: the root's world rotation), unit quaternions.
    root_pos : array (3,)
        World root position, metres.
    offsets : array (J, 3)
        Bone offsets, metres.
    joints : sequence of int
        Joints wanted.
    parents : sequence of int, length J

    Returns
    -------
    positions : ndarray (len(joints), 3)
        World positions, metres (equal to :func:`fk`'s rows for those joints).
    rotations : ndarray (len(joints), 4)
        World rotations.
    """
    local = local_rot.tolist() if isinstance(local_rot, np.ndarray) else local_rot
    off = offsets.tolist() if isinstance(offsets, np.ndarray) else offsets
    world: dict[int, tuple] = {0: (tuple(local[0]), tuple(float(v) for v in root_pos))}

    def place(j: int) -> tuple:
        if j not in world:
            q0, (px, py, pz) = place(int(parents[j]))
            w0, x0, y0, z0 = q0
            ox, oy, oz = off[j]
            # p + q o q*, with t = 2 (v x o): o + w t + v x t
            tx, ty, tz = 2.0 * (y0 * oz - z0 * oy), 2.0 * (z0 * ox - x0 * oz), 2.0 * (x0 * oy - y0 * ox)
            pos = (
                px + ox + w0 * tx + y0 * tz - z0 * ty,
                py + oy + w0 * ty + z0 * tx - x0 * tz,
                pz + oz + w0 * tz + x0 * ty - y0 * tx,
            )
            world[j] = (QN.qmul(q0, local[j]), pos)
        return world[j]

    placed = [place(int(j)) for j in joints]
    return np.array([p for _, p in placed]), np.array([r for r, _ in placed])


def fk_matrices(local_mat, root_pos, offsets, parents=sk.PARENTS):
    """Like :func:`fk` with rotation matrices: what the solver and rotation losses use.

    Parameters
    ----------
    local_mat : array or Tensor (..., J, 3, 3)
        Local joint rotations as matrices (row 0: the root's world rotation).
    root_pos : (..., 3)
        World root position, metres.
    offsets : (J, 3) or (..., J, 3)
        Bone offsets, metres.
    parents : sequence of int, length J

    Returns
    -------
    positions : (..., J, 3)
        World joint positions, metres.
    rotations : (..., J, 3, 3)
        World joint rotation matrices.
    """
    pos, mats, _ = _forward(local_mat, root_pos, offsets, parents)
    return pos, mats


def _forward(local_mat, root_pos, offsets, parents, local_quat=None):
    """The one level-ordered pass (numpy or torch): each level's joints are placed at once
    from their parents' world matrices; with ``local_quat (..., J, 4)`` the world
    quaternions are composed along the same levels. Returns positions ``(..., J, 3)``,
    world matrices ``(..., J, 3, 3)`` and world quaternions ``(..., J, 4)`` or None."""
    lv = levels(tuple(int(p) for p in parents))
    if torch_of(local_mat) is None:
        return _forward_numpy(np.asarray(local_mat), np.asarray(root_pos), np.asarray(offsets), lv, local_quat)
    take, cat = _ops(local_mat)
    offsets = _offsets_like(offsets, local_mat)
    # one tensor per level, joined once at the end: a joint's parent is on the level above
    g_rot = [local_mat[..., :1, :, :]]
    g_pos = [root_pos[..., None, :]]
    g_q = None if local_quat is None else [local_quat[..., :1, :]]
    for idx, rows in zip(lv.joints, lv.level_parent_rows):
        pr = take(g_rot[-1], rows, -3)
        step = (pr @ take(offsets, idx, -2)[..., None])[..., 0]
        g_pos.append(take(g_pos[-1], rows, -2) + step)
        g_rot.append(pr @ take(local_mat, idx, -3))
        if g_q is not None:
            g_q.append(Q.mul(take(g_q[-1], rows, -2), take(local_quat, idx, -2)))
    order = lv.unorder
    return (
        take(cat(g_pos, -2), order, -2),
        take(cat(g_rot, -3), order, -3),
        None if g_q is None else take(cat(g_q, -2), order, -2),
    )


def _forward_numpy(
    local_mat: np.ndarray, root_pos: np.ndarray, offsets: np.ndarray, lv: Levels, local_quat: np.ndarray | None
) -> tuple[np.ndarray, np.ndarray, np.ndarray | None]:
    """:func:`_forward` for numpy: :func:`fk_level_order` on the joints gathered into level
    order, then gathered back."""
    order = lv.order
    quats = None
    if local_quat is not None:
        lq = local_quat[..., order, :]
        quats = np.empty(lq.shape)
        quats[..., 0, :] = lq[..., 0, :]
        start = 1
        for rows in lv.parent_rows:
            end = start + len(rows)
            quats[..., start:end, :] = Q.mul(quats[..., rows, :], lq[..., start:end, :])
            start = end
    pos, world = fk_level_order(local_mat[..., order, :, :], root_pos, offsets[..., order[1:], :, None], lv)
    back = lv.unorder
    return pos[..., back, :], world[..., back, :, :], None if quats is None else quats[..., back, :]


def fk_level_order(
    local_mat: np.ndarray, root_pos: np.ndarray, bone_offsets: np.ndarray, lv: Levels
) -> tuple[np.ndarray, np.ndarray]:
    """The numpy FK pass on joints stored in level order (:attr:`Levels.order`): each
    level's world rotations are one product written in place, then every position at once
    from the world bone vectors (numpy's per-call overhead, not arithmetic, is what one
    pose costs, hence few, larger calls). The solver's chain keeps its poses in this order.

    Parameters
    ----------
    local_mat : ndarray (..., J, 3, 3)
        Local rotations in level order (row 0: the root's world rotation).
    root_pos : ndarray (..., 3)
        World root position, metres.
    bone_offsets : ndarray (..., J - 1, 3, 1)
        The offsets of rows ``1 ..`` (``offsets[..., order[1:], :, None]``), metres.
    lv : Levels

    Returns
    -------
    positions : ndarray (..., J, 3)
        World positions, level order, metres.
    rotations : ndarray (..., J, 3, 3)
        World rotation matrices, level order.
    """
    lead, root_lead, bone_lead = local_mat.shape[:-3], root_pos.shape[:-1], bone_offsets.shape[:-3]
    # the solver's case first (offsets shared or per pose, one root per pose): no broadcast_shapes call
    shared = root_lead == lead and bone_lead in (lead, ())
    shape = lead if shared else np.broadcast_shapes(lead, root_lead, bone_lead)
    world = np.empty(shape + local_mat.shape[-3:])
    world[..., 0, :, :] = local_mat[..., 0, :, :]
    start = 1
    for rows, view in zip(lv.parent_rows, lv.parent_slices):
        end = start + len(rows)
        parent = world.take(rows, axis=-3) if view is None else world[..., view, :, :]
        np.matmul(parent, local_mat[..., start:end, :, :], out=world[..., start:end, :, :])
        start = end
    bones = np.matmul(world.take(lv.prow[1:], axis=-3), bone_offsets)[..., 0]
    pos = np.matmul(lv.chain, bones)
    pos += root_pos[..., None, :]
    return pos, world


def local_from_global(global_rot, parents=sk.PARENTS):
    """Local rotations ``(..., J, 4)`` from world rotations ``(..., J, 4)``."""
    par = np.array([0] + [int(p) for p in parents[1:]])
    take, cat = _ops(global_rot)
    rel = Q.mul(Q.conjugate(take(global_rot, par[1:], -2)), global_rot[..., 1:, :])
    return cat((global_rot[..., :1, :], rel), -2)
