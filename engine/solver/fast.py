"""The solver's fast path: one optimizer iteration with hand-derived gradients (numpy).

Used when every enabled constraint has a fast-path term
(:meth:`engine.constraints.base.Constraint.fast_term`) and the decoder can be fused
(:class:`DenseDecoder`). The trackers (``sensor``) and the ``temporal_prior`` are
evaluated here in batched arrays; every other kind's term (:mod:`engine.constraints.terms`)
adds its loss and its gradients w.r.t. the joint positions and rotations. A kind without
a term sends the frame to the reference path (autograd through the torch decoder), which
computes the same function; tests compare the two for every kind.

Per iteration (``L`` latent size, ``S`` sensors)::

    out  = decoder(z)                          q_raw (22, 4), disp (3,)
    r    = canonical(q_raw / |q_raw|)          local rotations
    R0   = H R(r0) (or the hip sensor's),  p0 = p_prev + H disp (or the hip sensor's)
    P, W = FK by levels (matrices)             (22, 3), (22, 3, 3)
    P'   = P + (head_target - P[head])         when the head anchors the body
    loss = sum_s w_s (|P'[j_s] - t_s|^2 + rw_s (3 - <T_s, W[j_s]>) / 4) + w_p |z - z_pred|^2 / L
           + sum_e w_e loss_e(P', W)         (every other kind's term, engine/constraints/*.py)

and the reverse pass is the closed form in :meth:`FastPose.backward`.
"""

from __future__ import annotations

import math

import numpy as np

from engine import skeleton as sk
from engine.kinematics import quat_np as QN
from engine.kinematics.fk import levels
from engine.models.fused import DenseDecoder
from engine.constraints.terms import PoseTerm

_EPS = 1e-8  # quaternion normalisation floor, as in engine.kinematics.quaternion.normalize


def _levi_civita() -> np.ndarray:
    e = np.zeros((3, 3, 3))
    e[0, 1, 2] = e[1, 2, 0] = e[2, 0, 1] = 1.0
    e[0, 2, 1] = e[2, 1, 0] = e[1, 0, 2] = -1.0
    return e


_EPS3 = _levi_civita()
#: ``cross(a, b) = (a outer b).reshape(9) @ _CROSS``; ``axial(M) = M.reshape(9) @ _AXIAL``
#: (``(M21 - M12, M02 - M20, M10 - M01)``): one matmul each instead of a dozen small ops.
_CROSS = _EPS3.transpose(1, 2, 0).reshape(9, 3)
_AXIAL = _EPS3.transpose(2, 1, 0).reshape(9, 3)


def _cross(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Row-wise cross product of ``(N, 3)`` arrays (np.cross costs ~10x more at this size)."""
    return (a[:, :, None] * b[:, None, :]).reshape(-1, 9) @ _CROSS


def _axial(m: np.ndarray) -> np.ndarray:
    """Axial vectors ``(N, 3)`` of the antisymmetric parts (times 2) of ``m (N, 3, 3)``."""
    return m.reshape(-1, 9) @ _AXIAL


class FastTerms:
    """The frame's terms (parameters frozen for the frame): sensors and the prior as arrays.

    Parameters
    ----------
    sensors : list of SensorConstraint
    prior : TemporalPriorConstraint or None
    weights_prior : float
        The prior's weight this frame.
    prediction : ndarray (L,) or None
        The predictor's latent.
    extras : list of PoseTerm
        Every other constraint's term (:mod:`engine.constraints.terms`).
    sensor_weights : list of float, optional
        The sensors' weights this frame (default: their ``weight``).

    Attributes
    ----------
    names : list of str
        Term names in evaluation order (sensors, the extras, then the prior if present).
    """

    def __init__(self, sensors: list, prior, weights_prior: float, prediction: np.ndarray | None,
                 extras: list[PoseTerm] | None = None, sensor_weights: list[float] | None = None) -> None:  # fmt: skip
        self.extras = extras or []
        self.names = ([c.name for c in sensors] + [e.name for e in self.extras]
                      + ([prior.name] if prior is not None else []))  # fmt: skip
        sw = [c.weight for c in sensors] if sensor_weights is None else list(sensor_weights)
        self.weights = np.array(sw + [e.weight for e in self.extras]
                                + ([weights_prior] if prior is not None else []))  # fmt: skip
        self.joint = np.array([sk.JOINT_INDEX[c.joint] for c in sensors], dtype=np.intp)
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

    Joints are stored in level order (root, then depth 1, 2, ...; :func:`levels`), so
    each FK level is one contiguous slice: a level's world rotations are one gather of
    the parents and one stacked product written in place, and the positions follow for
    all joints at once as ``root + ancestors @ (W_parent offset)``. The per-call numpy
    overhead, not arithmetic, is what one 22-joint pose costs, hence few, larger calls.

    Parameters
    ----------
    decoder : DenseDecoder
    offsets : ndarray (22, 3)
        Bone offsets, metres.
    """

    def __init__(self, decoder: DenseDecoder, offsets: np.ndarray) -> None:
        self.decoder = decoder
        n = self.n = sk.NUM_JOINTS
        lv = levels(sk.PARENTS)
        self.order = np.concatenate([[0], *lv.joints]).astype(np.intp)  # row -> joint
        self.row = np.asarray(lv.unorder, dtype=np.intp)  # joint -> row
        prow = np.concatenate([[0], *lv.parent_rows]).astype(np.intp)  # row -> parent's row (root: itself)
        self.prow = prow
        bounds = np.cumsum([1] + [len(j) for j in lv.joints])
        self.level_slices = [(int(a), int(b), prow[a:b]) for a, b in zip(bounds[:-1], bounds[1:])]
        self.q_index = (4 * self.order[:, None] + np.arange(4)).reshape(-1)  # decoder output -> level order
        offsets = np.asarray(offsets, dtype=np.float64)
        self.offsets = offsets
        self.off_col = offsets[self.order][1:, :, None]  # (21, 3, 1), rows 1..
        # chain[r, b]: 1 when bone b (the bone into row b + 1) lies on the path root -> row r;
        # subtree[r, d]: 1 when row d is row r or below it
        chain = np.zeros((n, n - 1))
        for r in range(1, n):
            a = r
            while a != 0:
                chain[r, a - 1] = 1.0
                a = prow[a]
        self.chain = chain
        self.subtree = np.ones((n, n))
        self.subtree[1:] = chain.T  # bone r - 1 ends at row r
        self._out = np.zeros(4 * n + 3, dtype=np.float32)

    def setup(self, heading: np.ndarray, prev_pos: np.ndarray, override_pos: np.ndarray | None,
              override_rot: np.ndarray | None, anchor_joint: int | None, anchor_pos: np.ndarray | None,
              terms: FastTerms) -> None:  # fmt: skip
        """Frame constants: heading ``(4,)`` of the previous root, its position ``(3,)``,
        the hip sensor's position/rotation (or None), the anchor joint and its target."""
        self.h = QN.to_matrix(heading)
        self.prev_pos = prev_pos
        self.override_pos = override_pos
        self.override_rot = None if override_rot is None else QN.to_matrix(override_rot)
        self.anchor = None if anchor_joint is None or override_pos is not None else int(self.row[anchor_joint])
        self.anchor_pos = anchor_pos
        self.terms = t = terms
        n = self.n
        self.rows = self.row[t.joint]  # sensor rows
        self.rows6 = self.rows[t.six]
        w = t.weights[: t.n_sensors] * t.on
        self.w2 = (2.0 * w)[:, None]
        self.rot_coef = -0.25 * w[t.six] * t.rot_weight
        # points whose position gradient is not zero: the sensors (and the anchor, which
        # takes minus their sum), with the subtree columns of each
        pts = self.rows if not t.extras else np.concatenate((self.rows, np.arange(n)))  # extras: every row
        pts = pts if self.anchor is None else np.append(pts, self.anchor)
        self.points = pts
        self.turns = any(e.turns for e in t.extras)
        self.sub_points = self.subtree[:, pts]
        self.sub_rot = self.subtree[:, self.rows6]

    # -- forward -------------------------------------------------------------------
    def forward(self, z: np.ndarray) -> np.ndarray:
        """Per-term losses ``(K,)`` at latent ``z (L,)`` float32; keeps what :meth:`backward` needs."""
        return self.after_decoder(z, self.decoder.forward(z))

    def after_decoder(self, z: np.ndarray, out: np.ndarray) -> np.ndarray:
        """The part of :meth:`forward` after the decoder (FK and losses)."""
        n, t = self.n, self.terms
        q = out[self.q_index].astype(np.float64).reshape(n, 4)
        norm = np.sqrt(np.einsum("ij,ij->i", q, q))
        np.maximum(norm, _EPS, out=norm)
        u = q / norm[:, None]
        local = QN.to_matrix(u)  # R(u) = R(-u): the canonical sign does not matter here
        world = np.empty((n, 3, 3))
        world[0] = self.override_rot if self.override_rot is not None else self.h @ local[0]
        for a, b, parents in self.level_slices:
            np.matmul(world[parents], local[a:b], out=world[a:b])
        bones = np.matmul(world[self.prow[1:]], self.off_col)[:, :, 0]  # (21, 3)
        root = self.override_pos if self.override_pos is not None else self.prev_pos + self.h @ out[4 * n:]
        pos = self.chain @ bones
        pos += root if self.anchor is None else self.anchor_pos - pos[self.anchor]
        self.norm, self.u, self.world_lo, self.pos_lo, self.z = norm, u, world, pos, z
        self.err = pos[self.rows] - t.target
        self.pos_loss = losses = np.einsum("ij,ij->i", self.err, self.err)
        if len(t.six):
            c = (3.0 - np.einsum("kij,kij->k", t.rot_target, world[self.rows6])) * 0.25
            self.rot_raw = c
            self.rot_loss = np.clip(c, 0.0, 1.0)
            losses = losses.copy()
            losses[t.six] += t.rot_weight * self.rot_loss
        losses = losses * t.on
        if t.extras:  # each term's loss, and its gradients for backward (joint order)
            self.pos_j, self.world_j = pos_j, world_j = pos[self.row], world[self.row]
            self.g_extra, self.g_turn = ge, gr = np.zeros((n, 3)), np.zeros((n, 3))
            losses = np.append(losses, [e.evaluate(pos_j, world_j, ge, gr) for e in t.extras])
        if t.has_prior:
            if t.prediction is None:
                return np.append(losses, 0.0)
            d = z - t.prediction
            return np.append(losses, np.dot(d, d) / len(d))
        return losses

    # joint-order views of the last forward pass (for the frame's result)
    @property
    def pos(self) -> np.ndarray:
        """World joint positions ``(22, 3)``, metres."""
        return self.pos_lo[self.row]

    @property
    def world(self) -> np.ndarray:
        """World joint rotation matrices ``(22, 3, 3)``."""
        return self.world_lo[self.row]

    @property
    def r(self) -> np.ndarray:
        """Local rotations ``(22, 4)``: unit quaternions with ``w >= 0`` (row 0 before the heading)."""
        u = self.u[self.row]
        return u * np.where(u[:, :1] < 0, -1.0, 1.0)

    # -- reverse -------------------------------------------------------------------
    def backward(self) -> np.ndarray:
        """Gradient of ``sum(weights * losses)`` w.r.t. the decoder output ``(91,)`` float32,
        for the state of the last :meth:`forward`.

        Instead of walking the levels backwards, it uses what a joint's rotation does to
        its subtree: turning joint ``j`` by a small world-frame angle ``a`` moves every
        descendant ``d`` by ``a x (P_d - P_j)`` and turns its world rotation by ``a``.
        So the gradient w.r.t. that angle is ``tau_j = sum_{d in subtree(j)} (P_d x g_d
        + w_d) - P_j x sum_{d in subtree(j)} g_d`` (``g_d`` position gradients, non-zero
        only at the sensors and the anchor, or everywhere with whole-pose terms; ``w_d`` the axial part of ``g_W_d W_d^T``):
        products with constant subtree columns. A local quaternion ``u_j`` turned by
        ``du`` turns the joint by ``W_parent 2 vec(du u_j*)``, hence ``d loss / d u_j =
        2 (0, W_parent^T tau_j) u_j``, tangent to the unit sphere, so the normalisation
        only divides it by ``|q_j|`` (and the canonical sign drops out).
        """
        t, pos = self.terms, self.pos_lo
        g = self.w2 * self.err  # (S, 3) position gradients at the sensor rows
        if t.extras:  # other kinds' terms, evaluated by forward: a gradient at every row
            g = np.concatenate((g, self.g_extra[self.order]))
        if self.anchor is not None:
            g = np.concatenate((g, -g.sum(0, keepdims=True)))
        tau = self.sub_points @ _cross(pos[self.points], g) - _cross(pos, self.sub_points @ g)
        if self.turns:
            tau += self.subtree @ self.g_turn[self.order]  # turning a joint turns every joint of its subtree
        if len(t.six):
            inside = (self.rot_raw >= 0.0) & (self.rot_raw <= 1.0)
            m = np.matmul(t.rot_target, self.world_lo[self.rows6].transpose(0, 2, 1))
            tau += self.sub_rot @ (_axial(m) * (self.rot_coef * inside)[:, None])
        frame = self.world_lo[self.prow]
        frame[0] = self.h
        sigma = np.matmul(tau[:, None, :], frame)[:, 0]  # W_parent^T tau
        g_q = QN.mul(np.concatenate((np.zeros((self.n, 1)), sigma), axis=1), self.u)
        g_q *= (2.0 / self.norm)[:, None]
        if self.override_rot is not None:
            g_q[0] = 0.0
        out = self._out
        out[self.q_index] = g_q.reshape(-1)
        out[4 * self.n:] = 0.0 if self.override_pos is not None else self.h.T @ g.sum(0)
        return out

    def latent_gradient(self) -> np.ndarray:
        """Gradient of the weighted total w.r.t. ``z (L,)`` float32 (after :meth:`forward`)."""
        g = self.decoder.backward(self.backward())
        t = self.terms
        if t.has_prior and t.prediction is not None:
            g = g + (2.0 * t.weights[-1] / len(self.z) * (self.z.astype(np.float64) - t.prediction)).astype(np.float32)
        return g

    def satisfied(self) -> bool:
        """Every connected sensor within its tolerances and every other term satisfied
        (offline stopping rule)."""
        t = self.terms
        ok = (self.pos_loss <= t.pos_tol2) | (t.on == 0)
        if not ok.all():
            return False
        if len(t.six) and not ((self.rot_loss <= t.rot_tol) | (t.on[t.six] == 0)).all():
            return False
        return all(e.satisfied(self.pos_j, self.world_j) for e in t.extras)
