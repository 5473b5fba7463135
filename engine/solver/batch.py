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

from engine.constraints.residual import FrameRows, Term
from engine.models.fused import DenseDecoder
from engine.solver.chain import PoseChain, RootFrames
from engine.solver.objective import FastObjective, StoppingRule
from engine.solver.update import LatentUpdate


class BatchObjective(FastObjective):
    """The terms of ``C`` rows of frames (one frame per row at a time) as a function of
    their latents: the frame-by-frame :class:`~engine.solver.objective.FastObjective`'s
    rows (the same maths), with a weight per row and frame, each row's frame set by
    :meth:`set_row`, and each row's last pose kept.

    Parameters
    ----------
    decoder : DenseDecoder
        The fused decoder; its :meth:`~DenseDecoder.columns` take the rows' latents.
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
        self,
        decoder: DenseDecoder,
        offsets: np.ndarray,
        terms: list[Term],
        weights: np.ndarray,
        root: RootFrames,
        root_quat: np.ndarray,
    ) -> None:
        self.spans = np.cumsum([0] + [len(t.names) for t in terms])
        split = [weights[0, a:b] for a, b in zip(self.spans[:-1], self.spans[1:])]
        super().__init__(decoder, PoseChain(offsets), terms, split, root)
        self.weights, self.root_quat = weights, root_quat
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
        self.root_quat[row] = QN.canonicalize(root_rot)

    def evaluate_streams(self, z: np.ndarray, idx: np.ndarray) -> np.ndarray:
        """Losses ``(A, K)`` of the rows ``idx (A,)`` at latents ``z (A, L)`` float32 (one
        decoder pass for all of them); keeps what :meth:`gradient_streams` needs."""
        r = self.root
        assert r.position is not None and r.rotation is not None
        sub = RootFrames(r.heading[idx], r.previous[idx], r.position[idx], r.rotation[idx])
        out = self.decoder.columns(len(idx)).forward(z.T)
        values = self.evaluate_rows(out.T, z.astype(np.float64), sub, idx, True)
        self.pos[idx], self.local[idx] = self.P, self.chain.local()
        self.values[idx] = values
        return values

    def gradient_streams(self) -> np.ndarray:
        """The gradients ``(A, L)`` float32 of each evaluated row's weighted total w.r.t.
        its latent."""
        assert self.rows is not None
        g_out, g_z = self.pose_gradient(self.weights[self.rows])
        return self.decoder.columns(len(self.rows)).backward(g_out.T).T + g_z.astype(np.float32)

    def row(self, c: int) -> tuple[np.ndarray, np.ndarray]:
        """Row ``c``'s last evaluated pose: world positions ``(22, 3)`` and local rotations
        ``(22, 4)`` (``w >= 0``; the root's is the hip tracker's), joint order."""
        local = self.local[c].copy()
        local[0] = self.root_quat[c]
        return self.pos[c].copy(), local


def solve_streams(
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
        values = objective.evaluate_streams(z[idx], idx)
        total = (objective.weights[idx] * values).sum(1)
        stop = stopping.stop(total, objective.satisfied_rows, idx)
        if not stop.all():
            grad = objective.gradient_streams()
            keep = ~stop
            update.step_rows(z, grad[keep], idx[keep])
            stopping.stepped(idx[keep])
        for c in idx[stop]:
            done(int(c), int(stopping.steps[c]))
            if rule == "adam":
                update.restart_row(int(c))
            if not next_frame(int(c)):
                live.remove(int(c))
