"""What one frame's solve minimises, and the rule that stops it.

An :class:`Objective` is the weighted sum of a frame's terms (:mod:`engine.constraints.residual`)
as a function of the latent: :meth:`~Objective.evaluate` gives every constraint's loss,
:meth:`~Objective.gradient` the latent gradient of the weighted total at the last
evaluation, :meth:`~Objective.satisfied` whether every constraint allows the offline
solve to stop. Two objectives compute the same function from the same terms:

* :class:`FastObjective`: numpy, the fused decoder (:class:`~engine.models.fused.DenseDecoder`)
  and the closed-form chain (:class:`~engine.solver.chain.PoseChain`); what every frame
  uses when the decoder is the pose VAE;
* :class:`ReferenceObjective`: torch autograd through the decoder module and the
  terms' residuals on tensors; the reference tests compare with, and the path for other
  decoders.

:class:`StoppingRule` is the one stopping rule of the realtime, offline and batched solves.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Sequence
from typing import TYPE_CHECKING, Any, Protocol

import numpy as np

from engine.constraints.residual import NUMPY, FrameInputs, Term, torch_kit
from engine.constraints.term_stack import TermStack
from engine.solver.chain import PoseChain, RootFrames
from engine.solver.frame import SolveTimings

if TYPE_CHECKING:
    from engine.constraints.base import Constraint
    from engine.kinematics.pose_state import PoseState


def active_weights(constraints: Sequence["Constraint"], frame: int) -> tuple[list["Constraint"], list[float]]:
    """The constraints a frame is solved against and their weights: each enabled one's
    ``weight`` times its :meth:`~Constraint.activity` at ``frame``, those of weight 0
    left out (they would add nothing but a loss to report and a stop to wait for)."""
    weighted = [(c, c.weight * c.activity(frame)) for c in constraints if c.enabled]
    return [c for c, w in weighted if w > 0], [w for c, w in weighted if w > 0]


def build_terms(
    constraints: Sequence["Constraint"], weights: Sequence[float], frame: FrameInputs
) -> tuple[list[Term], list[np.ndarray]]:
    """The frame's terms, kind by kind (:meth:`~engine.constraints.base.Constraint.terms`),
    and each term's weights ``(n,)`` in the order of its :attr:`~Term.names`."""
    groups: dict[type[Constraint], list[int]] = {}
    for i, c in enumerate(constraints):
        groups.setdefault(type(c), []).append(i)
    terms, term_weights = [], []
    for cls, idx in groups.items():
        built = cls.terms([constraints[i] for i in idx], frame)
        at = 0
        for t in built:
            terms.append(t)
            term_weights.append(np.array([weights[i] for i in idx[at : at + len(t.names)]], dtype=np.float64))
            at += len(t.names)
    return terms, term_weights


class Objective(Protocol):
    """A frame's weighted objective as a function of the latent (module doc)."""

    names: list[str]
    weights: np.ndarray
    fast: bool

    def evaluate(self, z: np.ndarray, timings: SolveTimings, gradient: bool = True) -> np.ndarray:
        """Every constraint's loss ``(K,)`` at latent ``z (L,)`` float32; ``gradient=False``
        says no :meth:`gradient` is expected at this point (its Jacobians may be skipped;
        :meth:`gradient` still works, at the cost of making them then)."""
        ...

    def gradient(self) -> np.ndarray:
        """The gradient ``(L,)`` float32 of ``weights @ losses`` at the last evaluation."""
        ...

    def satisfied(self) -> bool:
        """Whether every constraint lets the offline solve stop, at the last evaluation."""
        ...

    def state(self, latent: Any) -> "PoseState":
        """The last evaluated pose as a detached :class:`PoseState` with ``latent``."""
        ...


def _flat(weights: list[np.ndarray]) -> np.ndarray:
    """The terms' weights ``(n_i,)`` in one array ``(K,)``, the objective's order."""
    return np.concatenate(weights) if weights else np.zeros(0)


class FastObjective:
    """numpy objective: fused decoder, :class:`PoseChain`, terms with their Jacobians.

    The maths works on ``A`` rows of frames at once (:meth:`evaluate_rows`,
    :meth:`pose_gradient`, :meth:`satisfied_rows`); a frame-by-frame solve is one row
    (:meth:`evaluate`, :meth:`gradient`, :meth:`satisfied`), the batched offline solve
    (:class:`engine.solver.batch.BatchObjective`) many.
    """

    fast = True

    def __init__(
        self,
        decoder: Any,
        chain: PoseChain,
        terms: list[Term],
        weights: list[np.ndarray],
        root: RootFrames,
        make_state: Callable[[Any, "FastObjective"], "PoseState"] | None = None,
    ) -> None:
        self.decoder, self.chain, self.root, self._make_state = decoder, chain, root, make_state
        self.terms, self.stack, self.weights = terms, TermStack(terms, chain.n), _flat(weights)
        self.names = self.stack.names
        self._row_weights = self.weights[None]

    def evaluate_rows(
        self, out: np.ndarray, z: np.ndarray, root: RootFrames, rows: np.ndarray | None, gradient: bool
    ) -> np.ndarray:
        """Losses ``(A, K)`` of ``A`` rows from their decoder outputs ``out (A, 91)``, latents
        ``z (A, L)`` float64 and roots; ``rows`` are the rows of the terms' per-frame
        parameters (None: the first ``A``). Keeps what :meth:`pose_gradient` needs (its
        Jacobians only with ``gradient``)."""
        self.P, self.W = self.chain.forward(out, root)
        self.z, self.rows = z, rows
        self._residuals(gradient)
        return self.stack.losses(self.r)

    def pose_gradient(self, weights: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Gradients of each row's weighted total (``weights (A, K)``, not changed in place
        between calls) at
        the last :meth:`evaluate_rows` w.r.t. its decoder outputs ``(A, 91)`` and w.r.t.
        its latent directly ``(A, L)`` float64 (terms on the latent)."""
        if not self.jac:  # evaluated without Jacobians: make them now
            self._residuals(True)
        # the gradients in the chain's level order: no gathers
        g_pos, g_rot, g_z = self.stack.gradients(self.res, self.r, weights, self.z.shape[1], self.chain.unorder)
        return self.chain.backward(g_pos, g_rot, level_order=True), g_z

    def _residuals(self, jac: bool) -> None:
        """Each term's residuals (with their Jacobians when ``jac``) at the kept poses."""
        self.res = [t.residual(NUMPY, self.P, self.W, self.z, jac=jac, rows=self.rows) for t in self.terms]
        self.r = self.stack.stack(self.res) if self.res else np.zeros((len(self.P), 0))
        self.jac = jac

    def satisfied_rows(self) -> np.ndarray:
        """Per row of the last :meth:`evaluate_rows` ``(A,)``: every constraint lets its
        frame stop."""
        ok = np.ones(len(self.P), dtype=bool)
        for t, r in zip(self.terms, self.res):
            ok &= t.satisfied_by(r, rows=self.rows).all(1)
        return ok

    def evaluate(self, z: np.ndarray, timings: SolveTimings, gradient: bool = True) -> np.ndarray:
        t0 = time.perf_counter()
        out = self.decoder.forward(z)
        t1 = time.perf_counter()
        values = self.evaluate_rows(out[None], z[None].astype(np.float64), self.root, None, gradient)
        timings.decoder += t1 - t0
        timings.fk_losses += time.perf_counter() - t1
        return values[0]

    def gradient(self) -> np.ndarray:
        g_out, g_z = self.pose_gradient(self._row_weights)
        return self.decoder.backward(g_out[0]) + g_z[0].astype(np.float32)

    def satisfied(self) -> bool:
        return bool(self.satisfied_rows()[0])

    def state(self, latent: Any) -> "PoseState":
        assert self._make_state is not None, "an objective of rows has no single state"
        return self._make_state(latent, self)


class ReferenceObjective:
    """torch objective: autograd through ``decode(z) -> PoseState`` and the terms."""

    fast = False

    def __init__(self, decode: Callable[[Any], "PoseState"], terms: list[Term], weights: list[np.ndarray]) -> None:
        self.decode, self.terms, self.weights = decode, terms, _flat(weights)
        self.names = [n for t in terms for n in t.names]

    def evaluate(self, z: np.ndarray, timings: SolveTimings, gradient: bool = True) -> np.ndarray:
        import torch

        from engine.constraints.base import state_arrays

        kit = torch_kit()
        t0 = time.perf_counter()
        self.z = torch.from_numpy(np.array(z, dtype=np.float32)).requires_grad_(True)
        self._state = self.decode(self.z)
        P, W, Z = state_arrays(self._state)
        parts = [t.losses(t.residual(kit, P, W, Z), kit)[0] for t in self.terms]
        values = torch.cat(parts) if parts else P.new_zeros(0)
        self.total = (torch.as_tensor(self.weights, dtype=values.dtype) * values).sum()
        timings.fk_losses += time.perf_counter() - t0
        return values.detach().double().numpy()

    def gradient(self) -> np.ndarray:
        import torch

        if not self.total.requires_grad:  # no term depends on the latent: nothing to move
            return np.zeros(self.z.shape, np.float32)
        (g,) = torch.autograd.grad(self.total, self.z)
        return g.numpy()

    def satisfied(self) -> bool:
        from engine.constraints.base import state_arrays

        P, W, Z = (a.detach().double().numpy() for a in state_arrays(self._state))
        return all(t.satisfied(P, W, Z).all() for t in self.terms)

    def state(self, latent: Any) -> "PoseState":
        out = self._state.detached()
        out.latent = latent
        return out


class StoppingRule:
    """When a solve of ``rows`` independent frames stops, per frame.

    A frame stops after ``cap`` steps; in ``offline`` mode also when every constraint is
    satisfied, or when its total has not improved by ``min_improvement`` (relative) for
    ``patience`` evaluations in a row. A frame given a fixed step count
    (:meth:`fix`) stops after exactly that many steps instead.
    """

    def __init__(self, cap: int, offline: bool, patience: int, min_improvement: float, rows: int = 1) -> None:
        self.cap, self.offline, self.patience, self.min_improvement = cap, offline, patience, min_improvement
        self.best = np.full(rows, np.inf)
        self.since = np.zeros(rows, np.intp)
        self.steps = np.zeros(rows, np.intp)
        self.fixed = np.full(rows, -1, np.intp)

    def fix(self, row: int, steps: int | None) -> None:
        """Row ``row``'s frame takes ``steps`` steps (None: the rule decides)."""
        self.fixed[row] = -1 if steps is None else steps

    def restart(self, row: int) -> None:
        """Row ``row`` starts a new frame."""
        self.best[row], self.since[row], self.steps[row] = np.inf, 0, 0

    def stop(
        self, total: np.ndarray, satisfied: Callable[[], np.ndarray], rows: np.ndarray | None = None
    ) -> np.ndarray:
        """Whether each of ``rows`` (default: all) stops at its latest evaluation (``total``,
        ``(A,)``); ``satisfied()`` is asked only when the offline rule needs it."""
        if rows is None and not self.offline and len(self.steps) == 1:  # one realtime frame: scalars
            return np.array([self.last(int(self.steps[0]))])
        rows = np.arange(len(self.best)) if rows is None else rows
        steps, fixed = self.steps[rows], self.fixed[rows]
        out = steps >= self.cap
        # the losses decide only rows with no fixed count that are short of the cap: with
        # none (the batched solve's fixed steps), neither the improvement record nor
        # ``satisfied()`` (every term's checks) can change the answer
        if self.offline and ((fixed < 0) & ~out).any():
            best = self.best[rows]
            better = total < best * (1.0 - self.min_improvement)
            self.best[rows] = np.where(better, total, best)
            self.since[rows] = np.where(better, 0, self.since[rows] + 1)
            out = out | (self.since[rows] >= self.patience) | satisfied()
        return np.where(fixed >= 0, steps >= fixed, out)

    def stop_one(self, total: float, satisfied: Callable[[], bool], steps: int) -> bool:
        """:meth:`stop` for a rule of one row whose frame has taken ``steps`` steps (the
        caller counts them: no :meth:`stepped`); a realtime frame answers from the count
        alone (no arrays)."""
        if not self.offline:
            return self.last(steps)
        self.steps[0] = steps
        return bool(self.stop(np.array([total]), lambda: np.array([satisfied()]))[0])

    def last(self, steps: int, row: int = 0) -> bool:
        """Whether row ``row``'s frame stops for certain once it has taken ``steps`` steps
        (at its cap or its fixed count), whatever its losses: no gradient follows."""
        fixed = int(self.fixed[row])
        return steps >= (fixed if fixed >= 0 else self.cap)

    def stepped(self, rows: np.ndarray | None = None) -> None:
        """Count one step of ``rows`` (default: all)."""
        if rows is None:
            self.steps += 1
        else:
            self.steps[rows] += 1
