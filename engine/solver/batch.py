"""Offline solves of many frames at once: one decoder pass for a column of latents.

The frame-by-frame offline solve (:mod:`engine.solver.optimizer`) multiplies the
decoder's matrices by one latent per call, up to 100 times per frame, reading the
~7 MB of weights each time. Here ``A`` frames that do not depend on each other are
solved together: every iteration is one decoder pass over all their latents (a matrix
product per block of the block-sparse stages, ``A`` columns wide), forward kinematics
and losses vectorised over the frames, the closed-form reverse pass of
:class:`engine.solver.fast.FastPose` vectorised the same way, and one update of every
latent. Each frame minimises what the frame-by-frame solve minimises (sensors, the
temporal prior's latent, the smoothing target from its two previous solved frames, the
ground band), keeps its own update state (Adam moments or plain steps), and stops by the
same rule or after a number of steps the caller gives per frame; under the same rule a
frame solved here is the frame-by-frame solve's, given the same start.

Which frames are independent is the caller's choice: :mod:`engine.methods.dragposer_batch`
cuts a clip into segments and solves the ``k``-th frame of every segment together, each
segment continuing from its own previous frame. The root is the hip tracker's in every
frame (position and rotation).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from engine.kinematics import quat_np as QN
from engine.models.fused import DenseDecoder
from engine.solver.fast import FastPose, _AXIAL, _CROSS
from engine.constraints.ground import _FEET, SOFTMIN_TAU
from engine.solver.update import LatentUpdate


class BatchDecoder:
    """:class:`DenseDecoder`'s block-sparse products on ``T`` latents at once (columns)."""

    def __init__(self, dense: DenseDecoder) -> None:
        self.dense = dense
        self._gates: list[np.ndarray] = []

    def forward(self, z: np.ndarray) -> np.ndarray:
        """``z (L, T)`` float32 -> decoder outputs ``(91, T)`` (quaternions, displacement)."""
        d, slope = self.dense, np.float32(self.dense.slope)
        x, last, self._gates = np.ascontiguousarray(z, dtype=np.float32), len(d.weights) - 1, []
        for i, runs in enumerate(d.forward_runs):
            y = np.zeros((d.weights[i].shape[0], x.shape[1]), np.float32)
            for r in runs:
                if r.c1 > r.c0:
                    np.dot(r.w, x[r.c0 : r.c1], out=y[r.r0 : r.r1])
            y += d.biases[i][:, None]
            if i < last:
                gate = np.where(y > 0, np.float32(1.0), slope)
                self._gates.append(gate)
                y *= gate
            x = y
        return x

    def backward(self, grad_out: np.ndarray) -> np.ndarray:
        """Gradients ``(L, T)`` w.r.t. the latents, for output gradients ``(91, T)``."""
        d = self.dense
        g = np.ascontiguousarray(grad_out, dtype=np.float32)
        for i in range(len(d.weights) - 1, -1, -1):
            if i < len(d.weights) - 1:
                g = g * self._gates[i]
            y = np.zeros((d.weights[i].shape[1], g.shape[1]), np.float32)
            for r in d.backward_runs[i]:
                if r.c1 > r.c0:
                    np.dot(r.w, g[r.c0 : r.c1], out=y[r.r0 : r.r1])
            g = y
        return g


@dataclass
class FrameTerms:
    """What ``T`` independent frames are solved against (``S`` sensors of which ``S6``
    give rotations; joint indices in the canonical skeleton's order).

    Attributes
    ----------
    joints : ndarray (S,) int
    targets : ndarray (T, S, 3)
        Sensor positions, metres.
    weights : ndarray (T, S)
        Sensor weights (0 for a frame where a sensor is not connected).
    six : ndarray (S6,) int
        Indices (in ``S``) of the sensors with rotations.
    rot_targets : ndarray (T, S6, 3, 3)
        Their world rotations.
    rot_weights : ndarray (T, S6)
        Rotation term weights against the squared position error.
    root_pos : ndarray (T, 3)
    root_rot : ndarray (T, 3, 3)
        The hip tracker's world pose per frame; ``root_quat (T, 4)`` the same rotation.
    prior : ndarray (T, L) or None
        The temporal prior's latents; ``prior_weight`` their weight.
    smooth_weight, ground_weight : float
    ground_band : (float, float)
        Band of the lower ankle's height, metres.
    smooth_target : ndarray (T, 22, 3)
        The smoothing term's targets (constant-velocity extrapolation of each frame's two
        previous solved poses), metres; ``smooth_on (T,)`` bool, where it acts.
    pos_tol2 : ndarray (S,)
        Squared position tolerances, m^2; ``rot_tol`` (S6,) the rotation tolerances as
        ``sin^2(angle / 2)``.
    """

    joints: np.ndarray
    targets: np.ndarray
    weights: np.ndarray
    six: np.ndarray
    rot_targets: np.ndarray
    rot_weights: np.ndarray
    root_pos: np.ndarray
    root_rot: np.ndarray
    root_quat: np.ndarray
    prior: np.ndarray | None
    prior_weight: float
    smooth_weight: float
    ground_weight: float
    ground_band: tuple[float, float]
    smooth_target: np.ndarray
    smooth_on: np.ndarray
    pos_tol2: np.ndarray
    rot_tol: np.ndarray
    names: list[str] = field(default_factory=list)  # sensor term names, for the losses


class BatchPose:
    """Forward and closed-form reverse pass of FK and losses for the active frames of a
    batch (the per-frame formulas of :class:`engine.solver.fast.FastPose`, with a frame axis)."""

    def __init__(self, offsets: np.ndarray, dense: DenseDecoder) -> None:
        self.fp = FastPose(dense, np.asarray(offsets, dtype=np.float64))  # the level-order tables

    def setup(self, t: FrameTerms) -> None:
        fp, self.t = self.fp, t
        self.rows, self.rows6 = fp.row[t.joints], fp.row[t.joints[t.six]]
        self.feet = fp.row[_FEET]
        f = len(t.targets)
        self.pos = np.zeros((f, fp.n, 3))  # level order, the last evaluation of each frame
        self.world = np.zeros((f, fp.n, 3, 3))
        self.u = np.zeros((f, fp.n, 4))

    def forward(self, z: np.ndarray, out: np.ndarray, idx: np.ndarray) -> np.ndarray:
        """Per-frame losses ``(A, K)`` (sensors, then smooth, ground, prior) of the active
        frames ``idx (A,)`` at their latents ``z (A, L)`` float32 with decoder outputs
        ``out (91, A)``; keeps what :meth:`backward` needs."""
        fp, t = self.fp, self.t
        f, n = len(z), fp.n
        q = out[fp.q_index].T.astype(np.float64).reshape(f, n, 4)
        norm = np.sqrt(np.einsum("tij,tij->ti", q, q))
        np.maximum(norm, 1e-8, out=norm)
        u = q / norm[..., None]
        local = QN.to_matrix(u)
        world = np.empty((f, n, 3, 3))
        world[:, 0] = t.root_rot[idx]
        for a, b, parents in fp.level_slices:
            np.matmul(world[:, parents], local[:, a:b], out=world[:, a:b])
        bones = np.matmul(world[:, fp.prow[1:]], fp.off_col)[..., 0]  # (A, 21, 3)
        pos = np.matmul(fp.chain, bones) + t.root_pos[idx, None]
        self.pos[idx] = pos  # for row()
        self.world[idx], self.u[idx] = world, u
        self.idx, self.norm, self.z = idx, norm, z
        self._active = pos, world, u  # the same, for backward() without a gather
        self.err = pos[:, self.rows] - t.targets[idx]
        self.pos_loss = np.einsum("tsi,tsi->ts", self.err, self.err)
        w = t.weights[idx]
        sensors = self.pos_loss.copy()
        if len(t.six):
            c = (3.0 - np.einsum("tkij,tkij->tk", t.rot_targets[idx], world[:, self.rows6])) * 0.25
            self.rot_raw, self.rot_loss = c, np.clip(c, 0.0, 1.0)
            sensors[:, t.six] += t.rot_weights[idx] * self.rot_loss
        self.dev = (pos - t.smooth_target[idx][:, fp.order]) * t.smooth_on[idx, None, None]
        cols = [sensors * (w > 0), (self.dev**2).sum((1, 2))[:, None] / n]
        if t.ground_weight > 0:
            h = pos[:, self.feet, 2]
            m = h.min(1, keepdims=True)
            e = np.exp(-(h - m) / SOFTMIN_TAU)
            soft = m[:, 0] - SOFTMIN_TAU * np.log(e.sum(1))
            lo, hi = t.ground_band
            self.ground_w = e / e.sum(1, keepdims=True)
            self.ground_e = np.where(soft > hi, soft - hi, np.where(soft < lo, soft - lo, 0.0))
            cols.append(self.ground_e[:, None] ** 2)
        else:  # weight 0 (trackers on the feet): the term is not evaluated
            cols.append(np.zeros((f, 1)))
        if t.prior is not None:
            d = z.astype(np.float64) - t.prior[idx]
            cols.append((d * d).sum(1, keepdims=True) / z.shape[1])
        return np.concatenate(cols, axis=1)

    def term_weights(self) -> np.ndarray:
        """Weights ``(T, K)`` of :meth:`forward`'s columns, every frame."""
        t = self.t
        f = len(t.targets)
        extra = [np.full((f, 1), t.smooth_weight), np.full((f, 1), t.ground_weight)]
        if t.prior is not None:
            extra.append(np.full((f, 1), t.prior_weight))
        return np.concatenate([t.weights, *extra], axis=1)

    def backward(self) -> tuple[np.ndarray, np.ndarray | None]:
        """Gradients of the weighted totals w.r.t. the active frames' decoder outputs
        ``(91, A)`` float32 and w.r.t. their latents directly (the prior term) ``(A, L)``,
        for the last :meth:`forward`."""
        fp, t, idx = self.fp, self.t, self.idx
        f, n = len(idx), fp.n
        w = t.weights[idx]
        g = np.zeros((f, n, 3))
        g[:, self.rows] += (2.0 * w)[..., None] * self.err  # sensor joints are distinct
        if t.smooth_weight > 0:
            g += (2.0 * t.smooth_weight / n) * self.dev
        if t.ground_weight > 0:
            g[:, self.feet, 2] += (2.0 * t.ground_weight * self.ground_e)[:, None] * self.ground_w
        pos, world, u = self._active
        tau = np.matmul(fp.subtree, _cross3(pos, g)) - _cross3(pos, np.matmul(fp.subtree, g))
        if len(t.six):
            inside = (self.rot_raw >= 0.0) & (self.rot_raw <= 1.0)
            m = np.matmul(t.rot_targets[idx], world[:, self.rows6].transpose(0, 1, 3, 2))
            coef = -0.25 * w[:, t.six] * t.rot_weights[idx] * inside
            tau += np.matmul(fp.subtree[:, self.rows6], (m.reshape(f, -1, 9) @ _AXIAL) * coef[..., None])
        frame = world[:, fp.prow]
        sigma = np.einsum("tri,trij->trj", tau, frame)  # W_parent^T tau
        g_q = QN.mul(np.concatenate((np.zeros((f, n, 1)), sigma), axis=2), u)
        g_q *= (2.0 / self.norm)[..., None]
        g_q[:, 0] = 0.0  # the root's rotation and position are the hip tracker's
        out = np.zeros((4 * n + 3, f), np.float32)
        out[fp.q_index] = g_q.reshape(f, -1).T
        gz = None
        if t.prior is not None:
            gz = (2.0 * t.prior_weight / self.z.shape[1]) * (self.z.astype(np.float64) - t.prior[idx])
        return out, gz

    def row(self, c: int) -> tuple[np.ndarray, np.ndarray]:
        """Frame ``c``'s last evaluated pose: world positions ``(22, 3)`` and local rotations
        ``(22, 4)`` (``w >= 0``; the root's is the hip tracker's), joint order."""
        fp = self.fp
        u = self.u[c][fp.row]
        local = u * np.where(u[:, :1] < 0, -1.0, 1.0)
        local[0] = self.t.root_quat[c]
        return self.pos[c][fp.row], local

    def satisfied(self) -> np.ndarray:
        """Per active frame ``(A,)``: every connected sensor within its tolerances."""
        t, idx = self.t, self.idx
        w = t.weights[idx]
        ok = ((self.pos_loss <= t.pos_tol2) | (w <= 0)).all(1)
        if len(t.six):
            ok &= ((self.rot_loss <= t.rot_tol) | (w[:, t.six] <= 0)).all(1)
        return ok


def _cross3(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Cross products of ``(..., 3)`` arrays by one matmul (as :func:`engine.solver.fast._cross`)."""
    return (a[..., :, None] * b[..., None, :]).reshape(a.shape[:-1] + (9,)) @ _CROSS


def solve_streams(decoder: BatchDecoder, pose: BatchPose, terms: FrameTerms, z: np.ndarray, rule: str,
                  lr: float, max_iterations: int, patience: int, min_improvement: float,
                  load: Callable[[int], bool], done: Callable[[int, int], None],
                  fixed_steps: Callable[[int], int | None] | None = None) -> None:  # fmt: skip
    """Solve ``C`` streams of frames, one frame of each at a time, all in the same decoder
    passes. Row ``c`` of ``terms`` and of the latents ``z (C, L)`` float32 hold stream
    ``c``'s current frame; ``load(c)`` puts its next frame's terms into row ``c`` (its
    start is the latent left in ``z[c]``, the previous frame's) and returns False when
    the stream has no frame left; ``done(c, iterations)`` is called when row ``c``'s frame
    has stopped (its result is in ``z[c]``, :meth:`BatchPose.row` and
    :attr:`BatchPose.values`). A frame takes ``fixed_steps(c)`` steps (called after each
    ``load(c)``) or, where that is None or not given, stops by the frame-by-frame offline
    rule: it meets its tolerances, its loss has not improved by ``min_improvement``
    (relative) for ``patience`` iterations, or ``max_iterations`` are done. ``rule``: ``sgd`` (steps of
    ``lr`` times the gradient), ``adam`` (fresh moments per frame) or ``adam-carry``
    (moments carried from frame to frame of a stream)."""
    c_all, dim = z.shape
    pose.setup(terms)
    b1, b2 = LatentUpdate.BETAS
    m1, m2, steps = np.zeros((c_all, dim), np.float32), np.zeros((c_all, dim), np.float32), np.zeros(c_all)
    best, since, iters = np.full(c_all, np.inf), np.zeros(c_all, np.intp), np.zeros(c_all, np.intp)
    weights = pose.term_weights()  # a row's sensor columns change with its frame, the rest never
    pose.values = np.zeros(weights.shape)
    steps_of = np.full(c_all, -1, np.intp)  # each row's frame's step count (-1: the stopping rule)

    def next_frame(c: int) -> bool:
        if not load(c):
            return False
        weights[c, : terms.weights.shape[1]] = terms.weights[c]
        k = fixed_steps(c) if fixed_steps is not None else None
        steps_of[c] = -1 if k is None else k
        return True

    live = [c for c in range(c_all) if next_frame(c)]
    while live:
        idx = np.array(live, dtype=np.intp)
        w = weights[idx]
        values = pose.values[idx] = pose.forward(z[idx], decoder.forward(z[idx].T), idx)
        total = (w * values).sum(1)
        better = total < best[idx] * (1.0 - min_improvement)
        best[idx] = np.where(better, total, best[idx])
        since[idx] = np.where(better, 0, since[idx] + 1)
        rule_stop = pose.satisfied() | (since[idx] >= patience) | (iters[idx] >= max_iterations)
        stop = np.where(steps_of[idx] < 0, rule_stop, iters[idx] >= steps_of[idx])
        if not stop.all():
            g_out, g_z = pose.backward()
            grad = decoder.backward(g_out).T
            if g_z is not None:
                grad = grad + g_z.astype(np.float32)
            keep = ~stop
            grad, k = grad[keep], idx[keep]
            if rule == "sgd":
                z[k] -= np.float32(lr) * grad
            else:
                steps[k] += 1
                n = steps[k][:, None]
                m1[k] += np.float32(1 - b1) * (grad - m1[k])
                m2[k] = m2[k] * np.float32(b2) + np.float32(1 - b2) * grad * grad
                denom = np.sqrt(m2[k]) / np.sqrt(1 - b2**n).astype(np.float32) + np.float32(LatentUpdate.EPS)
                z[k] -= (lr / (1 - b1**n)).astype(np.float32) * (m1[k] / denom)
            iters[k] += 1
        for c in idx[stop]:
            done(int(c), int(iters[c]))
            best[c], since[c], iters[c] = np.inf, 0, 0
            if rule == "adam":
                m1[c], m2[c], steps[c] = 0.0, 0.0, 0
            if not next_frame(int(c)):
                live.remove(int(c))
