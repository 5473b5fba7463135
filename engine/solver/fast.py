"""The solver's fast path: one optimizer iteration with hand-derived gradients (numpy).

Used when every enabled term is a ``sensor`` or the ``temporal_prior`` (what a live or
offline reconstruction has) and the decoder can be fused (:class:`DenseDecoder`).
Any other constraint kind sends the frame to the reference path (autograd through the
torch decoder), which computes the same function; a test compares the two.

Per iteration (``L`` latent size, ``S`` sensors)::

    out  = decoder(z)                          q_raw (22, 4), disp (3,)
    r    = canonical(q_raw / |q_raw|)          local rotations
    R0   = H R(r0) (or the hip sensor's),  p0 = p_prev + H disp (or the hip sensor's)
    P, W = FK by levels (matrices)             (22, 3), (22, 3, 3)
    P'   = P + (head_target - P[head])         when the head anchors the body
    loss = sum_s w_s (|P'[j_s] - t_s|^2 + rw_s (3 - <T_s, W[j_s]>) / 4) + w_p |z - z_pred|^2 / L

and the reverse pass is the closed form in :meth:`FastPose.backward`.
"""

from __future__ import annotations

import math

import numpy as np

from engine import skeleton as sk
from engine.kinematics import quat_np as QN
from engine.kinematics.fk import levels
from engine.models.fused import DenseDecoder

_EPS = 1e-8  # quaternion normalisation floor, as in engine.kinematics.quaternion.normalize


def _cross(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Row-wise cross product of ``(N, 3)`` arrays (np.cross costs ~10x more at this size)."""
    return a[:, _YZX] * b[:, _ZXY] - a[:, _ZXY] * b[:, _YZX]


_YZX, _ZXY = np.array([1, 2, 0]), np.array([2, 0, 1])


class _Level:
    """One FK level: its joints and their parents."""

    def __init__(self, joints: np.ndarray, parents: np.ndarray) -> None:
        self.joints = joints
        self.parents = parents


class FastTerms:
    """The frame's sensor and prior terms as arrays (parameters frozen for the frame).

    Attributes
    ----------
    names : list of str
        Term names in evaluation order (sensors first, then the prior if present).
    """

    def __init__(self, sensors: list, prior, weights_prior: float, prediction: np.ndarray | None) -> None:
        self.names = [c.name for c in sensors] + ([prior.name] if prior is not None else [])
        self.weights = np.array([c.weight for c in sensors] + ([weights_prior] if prior is not None else []))
        self.joint = np.array([sk.JOINT_INDEX[c.joint] for c in sensors], dtype=np.intp)
        self.unique_joints = len(set(self.joint.tolist())) == len(self.joint)
        self.target = np.array([c.position for c in sensors], dtype=np.float64).reshape(-1, 3)
        self.on = np.array([float(c.connected) for c in sensors])
        six = [k for k, c in enumerate(sensors) if c.dof == 6]
        self.six = np.array(six, dtype=np.intp)
        q = np.array([sensors[k].rotation for k in six], dtype=np.float64).reshape(-1, 4)
        q = q / np.maximum(np.linalg.norm(q, axis=-1, keepdims=True), 1e-12)
        self.rot_target = QN.to_matrix(q)
        self.rot_weight = np.array([sensors[k].rotation_weight for k in six])
        self.pos_tol2 = np.array([c.position_tolerance ** 2 for c in sensors])
        self.rot_tol = np.array([math.sin(math.radians(sensors[k].rotation_tolerance) / 2) ** 2 for k in six])
        self.has_prior = prior is not None
        self.prediction = prediction
        self.n_sensors = len(sensors)


class FastPose:
    """Forward and reverse pass of decode -> root -> FK -> losses for one latent.

    Parameters
    ----------
    decoder : DenseDecoder
    offsets : ndarray (22, 3)
        Bone offsets, metres.
    """

    def __init__(self, decoder: DenseDecoder, offsets: np.ndarray) -> None:
        self.decoder = decoder
        self.offsets = np.asarray(offsets, dtype=np.float64)
        lv = levels(sk.PARENTS)
        par = np.array([0] + list(sk.PARENTS[1:]))
        self.levels = [_Level(j, par[j]) for j in lv.joints]
        self.off_col = self.offsets[:, :, None]  # (22, 3, 1)
        self.n = sk.NUM_JOINTS
        self.parent_index = par
        # subtree[j, d] = 1 when d is j or one of its descendants
        self.subtree = np.eye(self.n)
        for d in range(1, self.n):
            a = par[d]
            while True:
                self.subtree[a, d] = 1.0
                if a == 0:
                    break
                a = par[a]

    def setup(self, heading: np.ndarray, prev_pos: np.ndarray, override_pos: np.ndarray | None,
              override_rot: np.ndarray | None, anchor_joint: int | None, anchor_pos: np.ndarray | None,
              terms: FastTerms) -> None:  # fmt: skip
        """Frame constants: heading ``(4,)`` of the previous root, its position ``(3,)``,
        the hip sensor's position/rotation (or None), the anchor joint and its target."""
        self.h = QN.to_matrix(heading)
        self.prev_pos = prev_pos
        self.override_pos = override_pos
        self.override_rot = None if override_rot is None else QN.to_matrix(override_rot)
        self.anchor = anchor_joint if override_pos is None else None
        self.anchor_pos = anchor_pos
        self.terms = terms

    # -- forward -------------------------------------------------------------------
    def forward(self, z: np.ndarray) -> np.ndarray:
        """Per-term losses ``(K,)`` at latent ``z (L,)`` float32; keeps what :meth:`backward` needs."""
        out = self.decoder.forward(z)
        return self.after_decoder(z, out)

    def after_decoder(self, z: np.ndarray, out: np.ndarray) -> np.ndarray:
        """The part of :meth:`forward` after the decoder (FK and losses)."""
        n = self.n
        q = out[: 4 * n].astype(np.float64).reshape(n, 4)
        disp = out[4 * n:].astype(np.float64)
        norm = np.maximum(np.sqrt((q * q).sum(-1, keepdims=True)), _EPS)
        u = q / norm
        sign = np.where(u[:, :1] < 0, -1.0, 1.0)
        r = u * sign
        local = QN.to_matrix(r)
        self.q, self.norm, self.u, self.sign, self.r, self.local = q, norm, u, sign, r, local
        world = np.empty((n, 3, 3))
        pos = np.empty((n, 3))
        world[0] = self.override_rot if self.override_rot is not None else self.h @ local[0]
        pos[0] = self.override_pos if self.override_pos is not None else self.prev_pos + self.h @ disp
        for lv in self.levels:
            pw = world[lv.parents]
            pos[lv.joints] = pos[lv.parents] + (pw @ self.off_col[lv.joints])[..., 0]
            world[lv.joints] = pw @ local[lv.joints]
        if self.anchor is not None:
            pos = pos + (self.anchor_pos - pos[self.anchor])
        self.world, self.pos, self.z = world, pos, z
        t = self.terms
        self.err = pos[t.joint] - t.target
        self.pos_loss = (self.err * self.err).sum(-1)
        losses = self.pos_loss.copy()
        if len(t.six):
            c = (3.0 - (t.rot_target * world[t.joint[t.six]]).sum((-1, -2))) * 0.25
            self.rot_raw = c
            self.rot_loss = np.clip(c, 0.0, 1.0)
            losses[t.six] += t.rot_weight * self.rot_loss
        losses *= t.on
        if t.has_prior:
            if t.prediction is None:
                losses = np.append(losses, 0.0)
            else:
                d = z.astype(np.float64) - t.prediction
                losses = np.append(losses, (d * d).mean())
        return losses

    # -- reverse -------------------------------------------------------------------
    def backward(self) -> np.ndarray:
        """Gradient of ``sum(weights * losses)`` w.r.t. the decoder output ``(91,)`` float32,
        for the state of the last :meth:`forward`.

        Instead of walking the levels backwards, it uses what a joint's rotation does to
        its subtree: turning joint ``j`` by a small world-frame angle ``a`` moves every
        descendant ``d`` by ``a x (P_d - P_j)`` and turns its world rotation by ``a``.
        So the gradient w.r.t. that angle is ``tau_j = sum_{d in subtree(j)} (P_d x g_d
        + w_d) - P_j x sum_{d in subtree(j)} g_d`` (``g_d`` position gradients, ``w_d``
        the axial part of ``g_W_d W_d^T``): two products with the constant subtree
        matrix. A local quaternion ``r_j`` turned by ``dr`` turns the joint by
        ``W_parent 2 vec(dr r_j*)``, hence ``d loss / d r_j = 2 (0, W_parent^T tau_j) r_j``.
        """
        n, t = self.n, self.terms
        w = t.weights[: t.n_sensors] * t.on
        pos = self.pos
        g_pos = np.zeros((n, 3))
        gp = (2.0 * w)[:, None] * self.err
        if t.unique_joints:
            g_pos[t.joint] = gp
        else:
            np.add.at(g_pos, t.joint, gp)
        if self.anchor is not None:
            g_pos[self.anchor] -= g_pos.sum(0)
        moment = _cross(pos, g_pos)
        if len(t.six):
            inside = (self.rot_raw >= 0.0) & (self.rot_raw <= 1.0)
            coef = -0.25 * w[t.six] * t.rot_weight * inside
            jj = t.joint[t.six]
            m = (coef[:, None, None] * t.rot_target) @ self.world[jj].transpose(0, 2, 1)
            axial = np.stack((m[:, 2, 1] - m[:, 1, 2], m[:, 0, 2] - m[:, 2, 0], m[:, 1, 0] - m[:, 0, 1]), axis=-1)
            np.add.at(moment, jj, axial)
        tau = self.subtree @ moment - _cross(pos, self.subtree @ g_pos)
        frame = self.world[self.parent_index]
        frame[0] = self.h
        sigma = (frame.transpose(0, 2, 1) @ tau[:, :, None])[..., 0]
        g_r = 2.0 * QN.mul(np.concatenate((np.zeros((n, 1)), sigma), axis=1), self.r)
        if self.override_rot is not None:
            g_r[0] = 0.0
        g_q = g_r * (self.sign / self.norm)  # tangent to r: the normalisation's projection is identity
        g_disp = self.h.T @ g_pos.sum(0) if self.override_pos is None else np.zeros(3)
        return np.concatenate((g_q.reshape(-1), g_disp)).astype(np.float32)

    def latent_gradient(self) -> np.ndarray:
        """Gradient of the weighted total w.r.t. ``z (L,)`` float32 (after :meth:`forward`)."""
        g = self.decoder.backward(self.backward())
        t = self.terms
        if t.has_prior and t.prediction is not None:
            g = g + (2.0 * t.weights[-1] / len(self.z) * (self.z.astype(np.float64) - t.prediction)).astype(np.float32)
        return g

    def satisfied(self) -> bool:
        """Every connected sensor within its tolerances (offline stopping rule)."""
        t = self.terms
        ok = (self.pos_loss <= t.pos_tol2) | (t.on == 0)
        if not ok.all():
            return False
        if len(t.six):
            return bool(((self.rot_loss <= t.rot_tol) | (t.on[t.six] == 0)).all())
        return True
