"""Offline solves of many frames at once: one decoder pass for a column of latents.

The frame-by-frame offline solve (:mod:`engine.solver.optimizer`) multiplies the
decoder's matrices by one latent per call, up to 100 times per frame, reading the
~7 MB of weights each time. Here ``A`` frames that do not depend on each other are
solved together: every iteration is one decoder pass over all their latents (a matrix
product per block of the block-sparse stages, ``A`` columns wide), forward kinematics
and losses vectorised over the frames, the closed-form reverse pass of
:class:`engine.solver.chain.PoseChain`, and one update of every
latent. Each frame minimises the frame-by-frame solve's terms (the same
:class:`~engine.constraints.residual.Term` objects, given a frame axis: trackers, the
temporal prior's latent, the smoothing target from its two previous solved frames, the
ground band), through the same :class:`~engine.solver.chain.PoseChain`, keeps its own
update state (:meth:`~engine.solver.update.LatentUpdate.step_rows`), and stops by the same
:class:`~engine.solver.objective.StoppingRule` or after a number of steps the caller gives
per frame; under the same rule a frame solved here is the frame-by-frame solve's, given
the same start.

Which frames are independent is the caller's choice: :mod:`engine.methods.dragposer_batch`
cuts a clip into segments and solves the ``k``-th frame of every segment together, each
segment continuing from its own previous frame. The root is the hip tracker's in every
frame (position and rotation).
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from engine.constraints.residual import NUMPY, FrameRows, Term
from engine.models.fused import DenseDecoder
from engine.solver.chain import PoseChain, RootFrames
from engine.solver.objective import StoppingRule
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
            for r in d.forward_runs[i]:  # the forward rectangles, transposed
                if r.c1 > r.c0:
                    y[r.c0 : r.c1] += r.w.T @ g[r.r0 : r.r1]
            g = y
        return g


class BatchObjective:
    """The terms of ``C`` rows of frames (one frame per row at a time) as a function of
    their latents: the frame-by-frame :class:`~engine.solver.objective.FastObjective` with
    a frame axis.

    Parameters
    ----------
    offsets : ndarray (22, 3)
        Bone offsets, metres.
    terms : list of Term
        The terms, each with ``C`` rows where it has per-frame parameters
        (:meth:`~engine.constraints.residual.FrameRows.rows`); ``load`` callers write
        a row with :meth:`set_row`.
    weights : ndarray (C, K)
        Each row's weight of each constraint (``K`` = the terms' names, in order).
    root : RootFrames
        Each row's root (the hip tracker's: ``position (C, 3)`` and ``rotation (C, 3, 3)``).
    root_quat : ndarray (C, 4)
        The same rotations as quaternions (``w >= 0``), for :meth:`row`.
    """

    def __init__(
        self, offsets: np.ndarray, terms: list[Term], weights: np.ndarray, root: RootFrames, root_quat: np.ndarray
    ) -> None:
        self.chain = PoseChain(offsets)
        self.terms, self.weights, self.root, self.root_quat = terms, weights, root, root_quat
        self.names = [n for t in terms for n in t.names]
        self.spans = np.cumsum([0] + [len(t.names) for t in terms])
        c, n = len(weights), self.chain.n
        self.pos, self.local = np.zeros((c, n, 3)), np.tile([1.0, 0.0, 0.0, 0.0], (c, n, 1))
        self.values = np.zeros(weights.shape)

    def set_row(
        self, row: int, frame_terms: list[Term], weights: np.ndarray, root_pos: np.ndarray, root_rot: np.ndarray
    ) -> None:
        """Row ``row`` becomes a frame: its one-frame terms (the same kinds, in order), its
        weights ``(K,)`` and its root (hip tracker position ``(3,)``, rotation ``(4,)``)."""
        from engine.kinematics import quat_np as QN

        for t, f in zip(self.terms, frame_terms):
            if isinstance(t, FrameRows):
                t.set_row(row, f)
        self.weights[row] = weights
        r = self.root
        assert r.position is not None and r.rotation is not None  # a batch's rows have the hip's root
        r.position[row], r.rotation[row] = root_pos, QN.to_matrix(root_rot)
        self.root_quat[row] = root_rot if root_rot[0] >= 0 else -root_rot

    def evaluate(self, z: np.ndarray, out: np.ndarray, idx: np.ndarray) -> np.ndarray:
        """Losses ``(A, K)`` of the rows ``idx (A,)`` at latents ``z (A, L)`` with decoder
        outputs ``out (91, A)``; keeps what :meth:`gradient` needs."""
        r = self.root
        assert r.position is not None and r.rotation is not None
        sub = RootFrames(r.heading[idx], r.previous[idx], r.position[idx], r.rotation[idx])
        P, W = self.chain.forward(out.T, sub)
        z64 = z.astype(np.float64)
        self.idx, self.P, self.W, self.z = idx, P, W, z64
        self.res = [t.residual(NUMPY, P, W, z64, jac=True, rows=idx) for t in self.terms]
        values = np.concatenate([t.losses(res) for t, res in zip(self.terms, self.res)], axis=1)
        self.pos[idx], self.local[idx] = P, self.chain.local()
        self.values[idx] = values
        return values

    def gradient(self) -> tuple[np.ndarray, np.ndarray]:
        """Gradients of each row's weighted total w.r.t. its decoder outputs ``(91, A)``
        float32 and w.r.t. its latent directly ``(A, L)`` (terms on the latent)."""
        g_pos, g_rot, g_z = np.zeros_like(self.P), np.zeros_like(self.P), np.zeros_like(self.z)
        w = self.weights[self.idx]
        for k, (t, res) in enumerate(zip(self.terms, self.res)):
            t.accumulate(res, w[:, self.spans[k] : self.spans[k + 1]], g_pos, g_rot, g_z)
        return self.chain.backward(g_pos, g_rot).T, g_z

    def satisfied(self) -> np.ndarray:
        """Per evaluated row ``(A,)``: every constraint lets its frame stop."""
        ok = np.ones(len(self.idx), dtype=bool)
        for t, res in zip(self.terms, self.res):
            ok &= t.satisfied_by(res, rows=self.idx).all(1)
        return ok

    def row(self, c: int) -> tuple[np.ndarray, np.ndarray]:
        """Row ``c``'s last evaluated pose: world positions ``(22, 3)`` and local rotations
        ``(22, 4)`` (``w >= 0``; the root's is the hip tracker's), joint order."""
        local = self.local[c].copy()
        local[0] = self.root_quat[c]
        return self.pos[c].copy(), local


def solve_streams(
    decoder: BatchDecoder,
    objective: BatchObjective,
    z: np.ndarray,
    rule: str,
    lr: float,
    max_iterations: int,
    patience: int,
    min_improvement: float,
    load: Callable[[int], bool],
    done: Callable[[int, int], None],
    fixed_steps: Callable[[int], int | None] | None = None,
) -> None:
    """Solve ``C`` streams of frames, one frame of each at a time, all in the same decoder
    passes. Row ``c`` of ``objective`` and of the latents ``z (C, L)`` float32 hold stream
    ``c``'s current frame; ``load(c)`` puts its next frame into row ``c``
    (:meth:`BatchObjective.set_row`; its start is the latent left in ``z[c]``, the previous
    frame's) and returns False when the stream has no frame left; ``done(c, iterations)``
    is called when row ``c``'s frame has stopped (its result is in ``z[c]``,
    :meth:`BatchObjective.row` and :attr:`BatchObjective.values`). A frame takes
    ``fixed_steps(c)`` steps (called after each ``load(c)``) or, where that is None or not
    given, stops by the frame-by-frame offline rule (:class:`StoppingRule`). ``rule``:
    ``sgd`` (steps of ``lr`` times the gradient), ``adam`` (fresh moments per frame) or
    ``adam-carry`` (moments carried from frame to frame of a stream)."""
    c_all = len(z)
    stopping = StoppingRule(max_iterations, True, patience, min_improvement, rows=c_all)
    update = LatentUpdate(rule, lr)

    def next_frame(c: int) -> bool:
        if not load(c):
            return False
        stopping.restart(c)
        stopping.fix(c, fixed_steps(c) if fixed_steps is not None else None)
        return True

    live = [c for c in range(c_all) if next_frame(c)]
    while live:
        idx = np.array(live, dtype=np.intp)
        values = objective.evaluate(z[idx], decoder.forward(z[idx].T), idx)
        total = (objective.weights[idx] * values).sum(1)
        stop = stopping.stop(total, objective.satisfied, idx)
        if not stop.all():
            g_out, g_z = objective.gradient()
            grad = decoder.backward(g_out).T + g_z.astype(np.float32)
            keep = ~stop
            update.step_rows(z, grad[keep], idx[keep])
            stopping.stepped(idx[keep])
        for c in idx[stop]:
            done(int(c), int(stopping.steps[c]))
            if rule == "adam":
                update.restart_row(int(c))
            if not next_frame(int(c)):
                live.remove(int(c))
