"""Decoder output to world pose, and back: the numpy chain of the solver's fast paths.

Per frame (``A`` frames at once; ``A = 1`` frame by frame)::

    out  = decoder(z)                          q_raw (22, 4), disp (3,)
    u    = q_raw / |q_raw|                     local rotations
    R0, p0 = place_root(H, R(u0), p_prev, disp)   the root rule (or the hip tracker's root)
    P, W = fk_matrices(...)                    (22, 3), (22, 3, 3)  (engine.kinematics.fk)
    P'   = P + (head_target - P[head])         when the head anchors the body

:meth:`PoseChain.backward` turns the gradients of any loss w.r.t. ``P'`` and world turns
of ``W`` (what :meth:`engine.constraints.term_stack.TermStack.gradients` gives) into the
gradient w.r.t. the decoder output, in closed form: turning joint ``j`` by a small
world-frame angle ``a`` moves every descendant ``d`` by ``a x (P_d - P_j)`` and turns its
world rotation by ``a``, so the gradient w.r.t. that angle is ``tau_j = sum_{d in
subtree(j)} (P_d x g_d + w_d) - P_j x sum_{d in subtree(j)} g_d`` (``g_d`` position
gradients, ``w_d`` rotation gradients): products with constant subtree columns. A local
quaternion ``u_j`` turned by ``du`` turns the joint by ``W_parent 2 vec(du u_j*)``, hence
``d loss / d u_j = 2 (0, W_parent^T tau_j) u_j``, tangent to the unit sphere, so the
normalisation only divides it by ``|q_j|``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from engine import skeleton as sk
from engine.constraints.rotation_residual import EPS3
from engine.kinematics import quat_np as QN
from engine.kinematics.fk import fk_level_order, levels
from engine.kinematics.root import anchor_body, place_root

_EPS = 1e-8  # quaternion normalisation floor, as in engine.kinematics.quaternion.normalize
#: ``cross(a, b) = (a outer b).reshape(9) @ _CROSS``: one matmul instead of a dozen small ops.
_CROSS = EPS3.transpose(1, 2, 0).reshape(9, 3)


#: ``(0, s) * u = (s outer u).reshape(12) @ _PURE_MUL``: the Hamilton product of a pure
#: quaternion (rows of the product table whose first factor has no scalar part).
_PURE_MUL = QN.MUL_TABLE[4:]


def cross(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Cross products of ``(..., 3)`` arrays (np.cross costs ~10x more at this size)."""
    return (a[..., :, None] * b[..., None, :]).reshape(a.shape[:-1] + (9,)) @ _CROSS


@dataclass
class RootFrames:
    """Where each of ``A`` frames' root comes from.

    Attributes
    ----------
    heading : ndarray (A, 3, 3)
        Heading of the previous root (the decoder's root rotation and displacement are
        relative to it).
    previous : ndarray (A, 3)
        The previous root position, metres.
    position, rotation : ndarray (A, 3), (A, 3, 3) or None
        The hip tracker's root (it dictates the root; the rotation may be absent).
    anchor : int or None
        Joint (the head) whose tracker places the body when there is no hip tracker;
        ``anchor_position (A, 3)`` its target.
    """

    heading: np.ndarray
    previous: np.ndarray
    position: np.ndarray | None = None
    rotation: np.ndarray | None = None
    anchor: int | None = None
    anchor_position: np.ndarray | None = None


class PoseChain:
    """Forward and reverse pass of decoder output -> root -> FK for ``A`` frames (module doc).

    The pose is kept in level order (:func:`~engine.kinematics.fk.levels`: root, then
    depth 1, 2, ...), so FK is :func:`~engine.kinematics.fk.fk_level_order` and the
    reverse pass reads it without reordering; the gathers between the decoder's joint
    order and level order are index arrays made here once, and the two arrays the terms
    read (positions and rotations in joint order) are gathered back once per forward.

    Parameters
    ----------
    offsets : ndarray (22, 3)
        Bone offsets, metres.
    """

    def __init__(self, offsets: np.ndarray) -> None:
        n = self.n = sk.NUM_JOINTS
        self.offsets = np.asarray(offsets, dtype=np.float64)
        lv = self.levels = levels(sk.PARENTS)
        self.order, self.unorder, self.prow = lv.order, lv.unorder, lv.prow
        self.bone_offsets = self.offsets[lv.order[1:], :, None]  # (21, 3, 1)
        self.q_index = (4 * lv.order[:, None] + np.arange(4)).reshape(-1)  # decoder output -> level order
        # subtree[r, d]: 1 when row d is row r or below it (bone r - 1 ends at row r)
        self.subtree = np.ones((n, n))
        self.subtree[1:] = lv.chain.T

    def forward(self, out: np.ndarray, root: RootFrames) -> tuple[np.ndarray, np.ndarray]:
        """World positions ``(A, 22, 3)`` and rotations ``(A, 22, 3, 3)`` (joint order) of
        decoder outputs ``out (A, 91)``; keeps what :meth:`backward` needs."""
        n, a = self.n, len(out)
        # the gathers take (a third of fancy indexing's cost at these sizes)
        q = out.take(self.q_index, axis=1).astype(np.float64).reshape(a, n, 4)
        norm = np.sqrt(np.einsum("aij,aij->ai", q, q))
        np.maximum(norm, _EPS, out=norm)
        u = q / norm[..., None]
        local = QN.to_matrix(u)  # R(u) = R(-u): the canonical sign does not matter here
        local[:, 0], base = place_root(
            root.heading, local[:, 0], root.previous, out[:, 4 * n :], rotation=root.rotation, position=root.position
        )
        pos, world = fk_level_order(local, base, self.bone_offsets, self.levels)
        self.anchor = None if root.anchor is None or root.position is not None else int(self.unorder[root.anchor])
        if self.anchor is not None:
            pos = anchor_body(pos, self.anchor, root.anchor_position)
        self.root, self.norm, self.u, self.pos, self.world = root, norm, u, pos, world
        back = self.unorder
        return pos.take(back, axis=1), world.take(back, axis=1)

    def backward(self, g_pos: np.ndarray, g_rot: np.ndarray | None, level_order: bool = False) -> np.ndarray:
        """Gradient w.r.t. the decoder outputs ``(A, 91)`` float32 of a loss whose gradients
        are ``g_pos (A, 22, 3)`` w.r.t. the positions and ``g_rot (A, 22, 3)`` w.r.t. world
        turns of the rotations (None: zero), at the last :meth:`forward`: in joint order, or
        in the chain's level order (row ``unorder[j]`` for joint ``j``) with
        ``level_order``, which saves gathering them (:meth:`TermStack.gradients
        <engine.constraints.term_stack.TermStack.gradients>` writes that order when given
        :attr:`unorder`)."""
        n, root, pos = self.n, self.root, self.pos
        g = g_pos if level_order else g_pos[:, self.order]
        if self.anchor is not None:  # the anchor moves the whole body against the others' pull
            if level_order:
                g = g.copy()  # the caller's array stays as given
            g[:, self.anchor] -= g.sum(1)
        tau = self.subtree @ cross(pos, g) - cross(pos, self.subtree @ g)
        if g_rot is not None:  # turning a joint turns every joint of its subtree
            tau += self.subtree @ (g_rot if level_order else g_rot[:, self.order])
        frame = self.world.take(self.prow, axis=1)
        frame[:, 0] = root.heading
        sigma = np.matmul(tau[..., None, :], frame)[..., 0, :]  # W_parent^T tau
        g_q = (sigma[..., :, None] * self.u[..., None, :]).reshape(sigma.shape[:-1] + (12,)) @ _PURE_MUL
        g_q *= (2.0 / self.norm)[..., None]
        if root.rotation is not None:
            g_q[:, 0] = 0.0
        out = np.zeros((len(pos), 4 * n + 3), np.float32)
        out[:, self.q_index] = g_q.reshape(len(pos), -1)
        if root.position is None:
            out[:, 4 * n :] = np.einsum("aji,aj->ai", root.heading, g.sum(1))
        return out

    def local(self) -> np.ndarray:
        """Local rotations ``(A, 22, 4)`` (joint order) of the last :meth:`forward`: unit
        quaternions with ``w >= 0``, row 0 before the heading (the decoder's own)."""
        return QN.canonicalize(self.u[:, self.unorder])
