"""Term forces: which loss term pulls a frame's latent where, at every iteration.

For each latent a solve visited (:attr:`engine.solver.Solution.path`), each enabled
term's weighted loss ``w * loss(decode(z))`` is differentiated with respect to ``z`` by
autograd through :meth:`engine.solver.PoseOptimizer.decode` and the term's own
:meth:`~engine.constraints.base.Constraint.loss`, one term at a time. The **force** of a
term is minus that gradient: the direction a plain gradient step would move the latent
for that term alone (Adam rescales the summed step per dimension, so the path follows
the sum only roughly). When two terms' forces point against each other they disagree
about the pose; the larger norm wins.

This replays the solve with the reference (autograd) losses, whichever path the solver
took; both compute the same losses (``tests/engine/test_solver_fast.py`` holds them equal).
"""

from __future__ import annotations

from collections.abc import Iterator, Sequence
from contextlib import contextmanager
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np
import torch

from engine.latent.projection import LatentMap
from engine.progress import CancelCheck, check
from engine.solver.threads import one_blas_thread

if TYPE_CHECKING:
    from engine.constraints.base import Constraint
    from engine.methods.solve_record import SolveRecord
    from engine.solver.frame import FrameContext
    from engine.solver.optimizer import PoseOptimizer


@dataclass(frozen=True)
class TermForces:
    """Per-iteration, per-term forces on the latent.

    Attributes
    ----------
    names : tuple of str
        Term (constraint) names, ``T`` of them.
    weights : ndarray (T,)
        Each term's weight in the frame (weight times activity).
    losses : ndarray (K, T)
        Weighted loss of each term at each visited latent.
    forces : ndarray (K, T, L)
        Minus the gradient of each weighted loss with respect to the latent.
    plane : ndarray (K, T, 2) or None
        ``forces`` projected on the latent map's plane (None without a map).
    """

    names: tuple[str, ...]
    weights: np.ndarray
    losses: np.ndarray
    forces: np.ndarray
    plane: np.ndarray | None = None

    @property
    def norms(self) -> np.ndarray:
        """Force norms ``(K, T)``."""
        return np.linalg.norm(self.forces, axis=-1)

    @property
    def total(self) -> np.ndarray:
        """Sum of the terms' forces ``(K, L)``: minus the solve's gradient."""
        return self.forces.sum(axis=1)

    def conflicts(self, k: int = -1) -> list[tuple[str, str, float]]:
        """Pairs of terms whose forces at iteration ``k`` point against each other
        (cosine below -0.5), with the cosine, most opposed first."""
        f = self.forces[k]
        n = np.linalg.norm(f, axis=1)
        out = []
        for i in range(len(self.names)):
            for j in range(i + 1, len(self.names)):
                if n[i] > 1e-9 and n[j] > 1e-9:
                    cos = float(f[i] @ f[j] / (n[i] * n[j]))
                    if cos < -0.5:
                        out.append((self.names[i], self.names[j], cos))
        return sorted(out, key=lambda t: t[2])


def term_forces(
    optimizer: "PoseOptimizer",
    ctx: "FrameContext",
    terms: Sequence[tuple["Constraint", float]],
    path: np.ndarray,
    latent_map: LatentMap | None = None,
    cancelled: CancelCheck | None = None,
) -> TermForces:
    """Each term's force at each latent of ``path``.

    Parameters
    ----------
    optimizer : PoseOptimizer
        Its :meth:`~PoseOptimizer.decode` gives the differentiable pose of a latent.
    ctx : FrameContext
        The frame's context, as the solve had it.
    terms : sequence of (Constraint, float)
        Constraints with their weights in this frame.
    path : ndarray (K, L)
        Latents visited by the solve, start first.
    latent_map : LatentMap, optional
        Projects the forces on the map's plane.
    cancelled : callable, optional
        Asked before each latent of the path; True raises :class:`engine.progress.Cancelled`.
    """
    path = np.asarray(path, dtype=np.float32).reshape(-1, np.shape(path)[-1])
    K, L, T = len(path), path.shape[1], len(terms)
    losses, forces = np.zeros((K, T)), np.zeros((K, T, L))
    with torch.enable_grad(), single_thread():
        for k in range(K):
            check(cancelled)
            z = torch.from_numpy(path[k].copy()).requires_grad_(True)
            state = optimizer.decode(z, ctx)
            values = [w * c.loss(state).reshape(()) for c, w in terms]
            losses[k] = [float(v.detach()) for v in values]
            forces[k] = _minus_gradients(values, z)
    plane = latent_map.project_direction(forces) if latent_map is not None else None
    names = tuple(c.name for c, _ in terms)
    return TermForces(names, np.array([w for _, w in terms], float), losses, forces, plane)


@contextmanager
def single_thread() -> Iterator[None]:
    """One torch thread and one BLAS thread for the body: these replays differentiate
    tiny tensors, where more threads only wait on each other (on the shared 2-core
    machine two threads made the forces of a frame four times slower)."""
    n = torch.get_num_threads()
    torch.set_num_threads(1)
    try:
        with one_blas_thread():
            yield
    finally:
        torch.set_num_threads(n)


def _minus_gradients(values: list[torch.Tensor], z: torch.Tensor) -> np.ndarray:
    """``-d values[t] / d z`` for each ``t``, ``(T, L)``, one backward pass per value (a
    batched pass, ``is_grads_batched``, took as long: measured on the shared machine)."""
    out = np.zeros((len(values), z.shape[0]))
    for t, v in enumerate(values):
        if v.requires_grad:  # else the term does not depend on the latent this frame
            (g,) = torch.autograd.grad(v, z, retain_graph=True, allow_unused=True)
            if g is not None:
                out[t] = -g.double().numpy()
    return out


def record_forces(
    method_optimizer: "PoseOptimizer",
    record: "SolveRecord",
    latent_map: LatentMap | None = None,
    cancelled: CancelCheck | None = None,
) -> TermForces:
    """:func:`term_forces` of a method's last :class:`~engine.methods.solve_record.SolveRecord`
    (its path; the final latent alone when the solver recorded none)."""
    path = getattr(record.solution, "path", None)
    if path is None:
        path = record.solution.latent.detach().numpy()[None]
    return term_forces(method_optimizer, record.context, record.terms, path, latent_map, cancelled)
