"""DragPoser's pose optimizer: Adam on the latent through a frozen decoder (Ponton et al.
2024, sec. 4.4 and Algorithm 1).

Per frame, the latent ``z (L,)`` starts from the temporal predictor's latent (or the
previous frame's), is decoded to a world pose (:mod:`engine.solver.pose`: forward
kinematics plus the root handling described there), and is moved by Adam against
``sum(weight_k * loss_k)`` over the enabled constraints (sensors, the temporal prior and
any user constraint). Two modes:

* ``realtime``: exactly ``iterations`` steps per frame;
* ``offline``: step until every constraint reports :meth:`~Constraint.satisfied` (the
  sensors' position and rotation tolerances), the loss stops improving, or
  ``max_iterations`` is reached.

A frame may also carry a **deadline** (:attr:`FrameContext.deadline`, a
``time.perf_counter`` time, set by a live loop; in either mode): after each step the
solver stops when one more step, at this frame's mean step time (gradient, update and evaluation), would
end past it; at
least one step is always taken. Adam's moments carry over as usual, so the next frame
continues from where this one stopped; :attr:`Solution.iterations` says how many steps
were taken. ``evaluate`` and ``reconstruct`` set no deadline.

Robustness: a constraint whose loss is NaN/inf at the starting latent is left out of
this frame's solve (with a warning); a loss or latent that becomes non-finite, or a
final loss far above the starting one (divergence), makes the frame fall back to its
starting latent, again with a warning. The caller's state is only ever updated from a
finite solution, so the next frame starts clean.

Two paths compute the same iterations: the **fast path** (:mod:`engine.solver.fast`,
hand-derived gradients through a fused decoder, numpy) whenever every enabled constraint
has a fast-path term (:meth:`~engine.constraints.base.Constraint.fast_term`, declared in
its kind's module) and the decoder is a :class:`~engine.models.PoseVAE`, and the
**reference path** (autograd through the torch decoder and every constraint's ``loss``)
otherwise, or when ``PoseOptimizer(..., fast=False)``. A frame that a kind without a
term sends to the reference path says so: :attr:`Solution.slow_kinds` names the kinds
and its warnings carry one line. Both use the update
rules of :mod:`engine.solver.update`. What a solve takes and returns (:class:`FrameContext`,
:class:`Solution`, :class:`SolveTimings`, the :class:`LatentDecoder` protocol) is
:mod:`engine.solver.frame`.
"""

from __future__ import annotations

import math
import time
import weakref
from collections.abc import Sequence
from typing import TYPE_CHECKING

import numpy as np
import torch

from engine.constraints.terms import FrameInputs, NativeTerm, PoseTerm
from engine.kinematics import quaternion as Q
from engine.kinematics.fk import fk_matrices
from engine.models.fused import DenseDecoder
from engine.models.vae import PoseVAE
from engine.solver.fast import FastPose, FastTerms
from engine.solver.frame import FrameContext, LatentDecoder, Solution, SolveTimings
from engine.solver.pose import world_root
from engine.solver.slow_path import report_slow
from engine.solver.threads import one_blas_thread
from engine.solver.settings import FULL_SET, OptimizerSettings
from engine.kinematics.pose_state import PoseState
from engine.solver.update import LatentUpdate

if TYPE_CHECKING:
    from engine.constraints.base import Constraint

_DENSE: "weakref.WeakKeyDictionary[torch.nn.Module, DenseDecoder]" = weakref.WeakKeyDictionary()


class PoseOptimizer:
    """Optimises one latent per frame through a frozen decoder.

    Parameters
    ----------
    decoder : LatentDecoder
        Frozen: a torch module is put in eval mode with ``requires_grad`` off, so only
        ``z`` gets gradients.
    offsets : array (22, 3)
        Bone offsets of the subject, metres.
    settings : OptimizerSettings
        Read at every :meth:`solve`, so edits apply from the next frame.
    fast : bool
        Use the fast path when the frame allows it (module doc); False forces the
        reference path (tests compare the two).
    """

    def __init__(self, decoder: LatentDecoder, offsets: np.ndarray, settings: OptimizerSettings | None = None,
                 fast: bool = True) -> None:  # fmt: skip
        self.decoder = decoder
        if isinstance(decoder, torch.nn.Module):  # frozen: no gradients for its weights
            decoder.eval().requires_grad_(False)
        self.settings = settings or OptimizerSettings()
        self.offsets = torch.as_tensor(np.asarray(offsets), dtype=torch.float32)
        self._fast: FastPose | None = None
        if fast and isinstance(decoder, PoseVAE):
            if decoder not in _DENSE:
                _DENSE[decoder] = DenseDecoder(decoder)
            self._fast = FastPose(_DENSE[decoder], np.asarray(offsets, dtype=np.float64))
        self._carry: dict = {}
        self._reported: set[tuple[str, ...]] = set()  # sets of slow kinds this solver has reported

    # -- decoding --------------------------------------------------------------------
    def decode(self, z: torch.Tensor, ctx: FrameContext) -> PoseState:
        """World pose of latent ``z (L,)`` in the context of a frame (differentiable)."""
        rot, disp = self.decoder.decode(z[None])
        return self._pose(rot[0], disp[0], z, ctx)

    def _pose(self, rot: torch.Tensor, disp: torch.Tensor, z: torch.Tensor, ctx: FrameContext) -> PoseState:
        root_rot, root_pos = world_root(rot[0], disp, ctx.previous_root, ctx.root_override)
        local = torch.cat((root_rot[None], rot[1:]), dim=0)
        pos, mats = fk_matrices(Q.to_matrix(local), root_pos, self.offsets)
        if ctx.root_anchor is not None and ctx.root_override is None:
            pos = ctx.root_anchor.apply(pos)
        return PoseState(pos, None, local, z, ctx.previous_positions, ctx.frame, ctx.prediction, mats)

    # -- solving ---------------------------------------------------------------------
    def solve(self, start: torch.Tensor, constraints: Sequence["Constraint"], ctx: FrameContext) -> Solution:
        """Optimise from latent ``start (L,)`` against the enabled ``constraints``, each
        weighted by its ``weight`` times its :meth:`~Constraint.activity` at ``ctx.frame``."""
        weighted = [(c, c.weight * c.activity(ctx.frame)) for c in constraints if c.enabled]
        terms = [c for c, w in weighted if w > 0]
        weights = {id(c): w for c, w in weighted if w > 0}
        with one_blas_thread():  # tiny products: one thread is fastest
            slow: list[str] = []
            if self._fast is not None:
                built = self._fast_terms(terms, weights, ctx)
                slow = sorted({c.kind for c, t in zip(terms, built) if t is None})
                if not slow and sum(c.kind == "temporal_prior" for c in terms) <= 1:
                    sol = self._solve_fast(start, terms, built, ctx)  # type: ignore[arg-type]
                    if sol is not None:
                        return sol
            sol = self._solve_reference(start, terms, weights, ctx)
            if slow:
                report_slow(sol, tuple(slow), self._reported)
            return sol

    @staticmethod
    def _fast_terms(terms: Sequence["Constraint"], weights: dict[int, float], ctx: FrameContext) -> list[PoseTerm | None]:
        """Each constraint's fast-path term for this frame with its frame weight (None: it has none)."""
        prev = ctx.previous_positions
        inputs = FrameInputs(None if prev is None else prev.detach().double().numpy(), ctx.frame)
        built = [c.fast_term(inputs) for c in terms]
        for c, t in zip(terms, built):
            if t is not None:
                t.weight = weights[id(c)]  # terms read it when evaluated: the activity counts
        return built

    def update_rule(self, terms: Sequence["Constraint"], deadline: bool = False) -> str:
        """The rule ``solve`` uses with these enabled ``terms``: ``auto`` is Adam with
        carried moments with at least :data:`FULL_SET` sensors, plain gradient steps with
        fewer. Under a ``deadline`` (live) ``auto`` takes Adam with fresh moments instead:
        carried moments make small steps, which ten iterations make up for but the three
        or four a deadline leaves do not (bundled clip, six sensors, ``evaluate
        --iterations 3``: 2.45 cm carried, 0.91 cm fresh; 2 iterations fresh: 1.01 cm)."""
        rule = self.settings.optimizer
        if rule == "auto":
            sensors = sum(1 for c in terms if c.kind == "sensor")
            rule = ("adam" if deadline else "adam-carry") if sensors >= FULL_SET else "sgd"
        return rule

    def _update(self, rule: str) -> LatentUpdate:
        s = self.settings
        if rule == "sgd":
            return LatentUpdate("sgd", s.step_size, s.momentum)
        return LatentUpdate(rule, s.lr, state=self._carry if rule == "adam-carry" else None)

    def _finish(self, z0: np.ndarray, z: np.ndarray, rule: str, upd: LatentUpdate, losses: list, steps: int,
                warnings: list[str], ctx: FrameContext, state_of, timings: SolveTimings) -> Solution:  # fmt: skip
        """Divergence check, moment carry-over and the detached result."""
        if losses[-1]["total"] > self.settings.divergence_factor * losses[0]["total"] + 1e-6:
            return self._fall_back(z0, ctx, losses, steps, warnings, "loss diverged", timings)
        # moments from before a stretch under another rule (a tracker was lost) describe
        # a different problem: start them afresh
        self._carry = upd.state if rule == "adam-carry" else {}
        latent = torch.from_numpy(z.copy())
        return Solution(latent, state_of(latent), losses, steps, warnings, timings=timings)

    def _solve_fast(self, start: torch.Tensor, terms: list, built: list[PoseTerm], ctx: FrameContext) -> Solution | None:
        """The fast path with the constraints' terms ``built``; None when the starting
        losses are not all finite (the reference path then drops the bad terms with its
        warning)."""
        s, fp, clock = self.settings, self._fast, time.perf_counter
        assert fp is not None
        native = [t for t in built if isinstance(t, NativeTerm)]
        sensors = [t for t in native if t.constraint.kind == "sensor"]
        prior = next((t for t in native if t.constraint.kind == "temporal_prior"), None)
        pred = None if ctx.prediction is None else ctx.prediction.detach().double().numpy()
        extras = [t for t in built if not isinstance(t, NativeTerm)]
        ft = FastTerms([t.constraint for t in sensors], None if prior is None else prior.constraint,
                       prior.weight if prior is not None else 0.0, pred, extras, [t.weight for t in sensors])  # fmt: skip
        ov, anchor = ctx.root_override, ctx.root_anchor
        fp.setup(Q.heading(ctx.previous_root.rotation.detach().double().numpy()),
                 ctx.previous_root.position.detach().double().numpy(),
                 None if ov is None else ov.position.detach().double().numpy(),
                 None if ov is None or ov.rotation is None else ov.rotation.detach().double().numpy(),
                 None if anchor is None else anchor.joint,
                 None if anchor is None else anchor.position.detach().double().numpy(), ft)  # fmt: skip
        z0 = start.detach().numpy().astype(np.float32)
        z, rule = z0.copy(), self.update_rule(terms, ctx.deadline is not None)
        upd, timings = self._update(rule), SolveTimings(fast=True)
        losses: list[dict[str, float]] = []
        path: list[np.ndarray] = []
        cap, offline = s.steps_cap(), s.mode == "offline"
        best, since_best, steps, warnings = math.inf, 0, 0, []
        deadline, cut, t_loop = ctx.deadline, False, clock()
        while True:
            t0 = clock()
            out = fp.decoder.forward(z)
            t1 = clock()
            values = fp.after_decoder(z, out)
            total = float(ft.weights @ values)
            t2 = clock()
            timings.decoder += t1 - t0
            timings.fk_losses += t2 - t1
            if steps == 0 and not np.isfinite(values).all():
                return None
            path.append(z)
            losses.append({**dict(zip(ft.names, values.tolist())), "total": total})
            if not math.isfinite(total) or not np.isfinite(z).all():
                return self._fall_back(z0, ctx, losses, steps, warnings, "loss became non-finite", timings)
            if steps >= cap:
                break
            if steps == 0:
                t_loop = clock()  # steps are timed from the first evaluation on
            elif deadline is not None and _past(deadline, t_loop, steps):
                cut = True
                break
            if offline:
                if fp.satisfied():
                    break
                if total < best * (1.0 - s.min_improvement):
                    best, since_best = total, 0
                else:
                    since_best += 1
                    if since_best >= s.patience:
                        break
            t0 = clock()
            grad = fp.latent_gradient()
            t1 = clock()
            z = upd.step(z, grad)
            timings.backward += t1 - t0
            timings.step += clock() - t1
            steps += 1
        timings.iterations = steps
        _to_ms(timings)
        sol = self._finish(z0, z, rule, upd, losses, steps, warnings, ctx, lambda lat: self._fast_state(lat, ctx),
                           timings)  # fmt: skip
        sol.cut = cut
        sol.path = np.stack(path)
        return sol

    def _fast_state(self, latent: torch.Tensor, ctx: FrameContext) -> PoseState:
        """The fast path's last evaluated pose as a (detached, float32) :class:`PoseState`."""
        fp = self._fast
        assert fp is not None
        local = fp.r.copy()
        ov = ctx.root_override
        if ov is not None and ov.rotation is not None:
            local[0] = ov.rotation.detach().double().numpy()
        else:
            local[0] = Q.mul(Q.heading(ctx.previous_root.rotation.detach().double().numpy()), fp.r[0])
        f = lambda a: torch.as_tensor(a, dtype=torch.float32)  # noqa: E731
        return PoseState(f(fp.pos), None, f(local), latent, ctx.previous_positions, ctx.frame, ctx.prediction,
                         f(fp.world))  # fmt: skip

    def _solve_reference(self, start: torch.Tensor, terms: list, weight_of: dict[int, float],
                         ctx: FrameContext) -> Solution:  # fmt: skip
        """Autograd through the torch decoder and every constraint's loss."""
        s, clock = self.settings, time.perf_counter
        warnings: list[str] = []
        z = start.detach().clone().requires_grad_(True)
        state = self.decode(z, ctx)
        values = _evaluate(terms, state)
        finite = torch.isfinite(values).tolist()
        if not all(finite):
            bad = [c.name for c, ok in zip(terms, finite) if not ok]
            warnings.append(f"non-finite loss ignored this frame: {', '.join(bad)}")
            terms = [c for c, ok in zip(terms, finite) if ok]
        terms, evaluate = _evaluator(terms, values)
        names = [c.name for c in terms]
        weights = torch.tensor([weight_of[id(c)] for c in terms], dtype=values.dtype)
        rule = self.update_rule(terms, ctx.deadline is not None)
        upd, timings = self._update(rule), SolveTimings()
        z0 = start.detach().numpy().astype(np.float32)
        losses: list[dict[str, float]] = []
        path: list[np.ndarray] = []
        cap, offline = s.steps_cap(), s.mode == "offline"
        best, since_best, steps = math.inf, 0, 0
        deadline, cut, t_loop = ctx.deadline, False, clock()
        while True:
            t0 = clock()
            rot, disp = self.decoder.decode(z[None])
            t1 = clock()
            state = self._pose(rot[0], disp[0], z, ctx)
            values = evaluate(state)
            total = (weights * values).sum()
            t2 = clock()
            timings.decoder += t1 - t0
            timings.fk_losses += t2 - t1
            path.append(z.detach().numpy().copy())
            losses.append({**dict(zip(names, values.detach().tolist())), "total": float(total.detach())})
            if not math.isfinite(losses[-1]["total"]) or not bool(torch.isfinite(z).all()):
                return self._fall_back(z0, ctx, losses, steps, warnings, "loss became non-finite", timings)
            if steps >= cap:
                break
            if steps == 0:
                t_loop = clock()  # steps are timed from the first evaluation on
            elif deadline is not None and _past(deadline, t_loop, steps):
                cut = True
                break
            if offline:
                if all(c.satisfied(state) for c in terms):
                    break
                if losses[-1]["total"] < best * (1.0 - s.min_improvement):
                    best, since_best = losses[-1]["total"], 0
                else:
                    since_best += 1
                    if since_best >= s.patience:
                        break
            t0 = clock()
            # no term left (e.g. every constraint outside its frame range): nothing to move
            (grad,) = torch.autograd.grad(total, z) if total.requires_grad else (torch.zeros_like(z),)
            t1 = clock()
            z = torch.from_numpy(upd.step(z.detach().numpy(), grad.numpy())).requires_grad_(True)
            timings.backward += t1 - t0
            timings.step += clock() - t1
            steps += 1
        timings.iterations = steps
        _to_ms(timings)
        final = state.detached()
        sol = self._finish(z0, z.detach().numpy(), rule, upd, losses, steps, warnings, ctx,
                           lambda lat: _with_latent(final, lat), timings)  # fmt: skip
        sol.cut = cut
        sol.path = np.stack(path)
        return sol

    def _fall_back(self, z0: np.ndarray, ctx: FrameContext, losses: list[dict[str, float]], steps: int,
                   warnings: list[str], why: str, timings: SolveTimings) -> Solution:  # fmt: skip
        warnings.append(f"{why}; frame kept its starting latent")
        z = torch.from_numpy(z0.copy())
        with torch.no_grad():
            state = self.decode(z, ctx)
        return Solution(z, state.detached(), losses, steps, warnings, fell_back=True, timings=timings)


def _past(deadline: float, t_loop: float, steps: int) -> bool:
    """Whether one more step, at the mean time of the ``steps`` taken since ``t_loop``,
    would end after ``deadline`` (all ``time.perf_counter`` seconds)."""
    now = time.perf_counter()
    return now + (now - t_loop) / steps > deadline


def _to_ms(t: SolveTimings) -> None:
    for k in ("decoder", "fk_losses", "backward", "step"):
        setattr(t, k, 1000.0 * getattr(t, k))


def _with_latent(state: PoseState, latent: torch.Tensor) -> PoseState:
    state.latent = latent
    return state


def _evaluate(terms: Sequence["Constraint"], state: PoseState) -> torch.Tensor:
    return torch.stack([c.loss(state).reshape(()) for c in terms]) if terms else state.positions.new_zeros(0)


def _evaluator(terms: list["Constraint"], like: torch.Tensor):
    """Reorder ``terms`` so kinds with a :meth:`~Constraint.batch` fast path come first,
    and return them with a function ``state -> (K,)`` losses in that order."""
    kinds: dict[type, list] = {}
    for c in terms:
        kinds.setdefault(type(c), []).append(c)
    fast, ordered, singles = [], [], []
    for cls, items in kinds.items():
        fn = cls.batch(items, like) if len(items) > 1 else None
        if fn is None:
            singles += items
        else:
            fast.append(fn)
            ordered += items

    def evaluate(state: PoseState) -> torch.Tensor:
        parts = [fn(state) for fn in fast]
        if singles:
            parts.append(_evaluate(singles, state))
        return torch.cat(parts) if parts else like.new_zeros(0)

    return ordered + singles, evaluate
