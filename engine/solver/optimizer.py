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

One loop (:meth:`PoseOptimizer.solve`) runs an :class:`~engine.solver.objective.Objective`
built from the frame's terms (each constraint kind's one residual,
:mod:`engine.constraints.residual`): the numpy :class:`~engine.solver.objective.FastObjective`
whenever the decoder is a :class:`~engine.models.PoseVAE`, the autograd
:class:`~engine.solver.objective.ReferenceObjective` otherwise or with
``PoseOptimizer(..., fast=False)``. Both use the update rules of
:mod:`engine.solver.update` and the :class:`~engine.solver.objective.StoppingRule`.
What a solve takes and returns (:class:`FrameContext`, :class:`Solution`,
:class:`SolveTimings`, the :class:`LatentDecoder` protocol) is :mod:`engine.solver.frame`.
"""

from __future__ import annotations

import math
import time
import weakref
from collections.abc import Sequence
from typing import TYPE_CHECKING

import numpy as np
import torch

from engine.constraints.residual import FrameInputs
from engine.kinematics import quat_np as QN
from engine.kinematics import quaternion as Q
from engine.kinematics.fk import fk_matrices
from engine.kinematics.pose_state import PoseState
from engine.kinematics.root import place_root
from engine.models.fused import DenseDecoder
from engine.models.vae import PoseVAE
from engine.solver.chain import PoseChain, RootFrames
from engine.solver.frame import FrameContext, LatentDecoder, Solution, SolveTimings
from engine.solver.objective import (
    FastObjective,
    Objective,
    ReferenceObjective,
    StoppingRule,
    active_weights,
    build_terms,
)
from engine.solver.pose import JointAnchor, RootAnchor
from engine.solver.settings import FULL_SET, OptimizerSettings
from engine.solver.threads import one_blas_thread
from engine.solver.update import LatentUpdate

if TYPE_CHECKING:
    from engine.constraints.base import Constraint

_DENSE: "weakref.WeakKeyDictionary[torch.nn.Module, DenseDecoder]" = weakref.WeakKeyDictionary()


def dense_decoder(vae: PoseVAE) -> DenseDecoder:
    """The fused numpy decoder of ``vae``: its matrices are made once per model (about
    0.8 CPU s), each call gets scratch buffers of its own
    (:meth:`~engine.models.fused.DenseDecoder.with_own_buffers`), so optimisers on one
    model, on one thread or several, never overwrite each other's activations."""
    if vae not in _DENSE:
        _DENSE[vae] = DenseDecoder(vae)
    return _DENSE[vae].with_own_buffers()


class FastParts:
    """What the fast objective needs from the model and the subject: the fused decoder and
    the pose chain."""

    def __init__(self, decoder: DenseDecoder, offsets: np.ndarray) -> None:
        self.decoder, self.chain = decoder, PoseChain(offsets)


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
        The default settings of :meth:`solve` (a solve may be given others).
    fast : bool
        Use the numpy objective when the decoder allows it (module doc); False forces the
        autograd reference (tests compare the two).
    """

    def __init__(
        self, decoder: LatentDecoder, offsets: np.ndarray, settings: OptimizerSettings | None = None, fast: bool = True
    ) -> None:
        self.decoder = decoder
        if isinstance(decoder, torch.nn.Module):  # frozen: no gradients for its weights
            decoder.eval().requires_grad_(False)
        self.settings = settings or OptimizerSettings()
        self.offsets = torch.as_tensor(np.asarray(offsets), dtype=torch.float32)
        self._fast: FastParts | None = None
        if fast and isinstance(decoder, PoseVAE):
            self._fast = FastParts(dense_decoder(decoder), np.asarray(offsets, dtype=np.float64))
        self._carry: dict = {}

    @property
    def fast_parts(self) -> FastParts | None:
        """The fused decoder and pose chain of the numpy objective (None: the reference runs)."""
        return self._fast

    # -- decoding --------------------------------------------------------------------
    def decode(self, z: torch.Tensor, ctx: FrameContext) -> PoseState:
        """World pose of latent ``z (L,)`` in the context of a frame (differentiable)."""
        rot, disp = self.decoder.decode(z[None])
        ov = ctx.root_override
        root_rot, root_pos = place_root(
            ctx.previous_root.heading(),
            rot[0][0],
            ctx.previous_root.position,
            disp[0],
            rotation=None if ov is None else ov.rotation,
            position=None if ov is None else ov.position,
        )
        local = torch.cat((root_rot[None], rot[0][1:]), dim=0)
        pos, mats = fk_matrices(Q.to_matrix(local), root_pos, self.offsets)
        if ctx.root_anchor is not None and ctx.root_override is None:
            pos = ctx.root_anchor.apply(pos)
        return PoseState(pos, None, local, z, ctx.previous_positions, ctx.frame, ctx.prediction, mats)

    # -- the objective -------------------------------------------------------------------
    def objective(self, constraints: Sequence["Constraint"], weights: Sequence[float], ctx: FrameContext) -> Objective:
        """The frame's objective over ``constraints`` with these ``weights`` (module doc)."""
        prev, pred = ctx.previous_positions, ctx.prediction
        inputs = FrameInputs(
            None if prev is None else prev.detach().double().numpy(),
            ctx.frame,
            None if pred is None else pred.detach().double().numpy(),
        )
        terms, term_weights = build_terms(constraints, weights, inputs)
        if self._fast is None:
            return ReferenceObjective(lambda z: self.decode(z, ctx), terms, term_weights)
        return FastObjective(
            self._fast.decoder,
            self._fast.chain,
            terms,
            term_weights,
            _root_frames(ctx),
            lambda latent, obj: _fast_state(latent, obj, ctx),
        )

    def update_rule(
        self, terms: Sequence["Constraint"], deadline: bool = False, settings: OptimizerSettings | None = None
    ) -> str:
        """The rule ``solve`` uses with these enabled ``terms``: ``auto`` is Adam with
        carried moments with at least :data:`FULL_SET` sensors, plain gradient steps with
        fewer. Under a ``deadline`` (live) ``auto`` takes Adam with fresh moments instead:
        carried moments make small steps, which ten iterations make up for but the three
        or four a deadline leaves do not (bundled clip, six sensors, ``evaluate
        --iterations 3``: 2.45 cm carried, 0.91 cm fresh; 2 iterations fresh: 1.01 cm)."""
        rule = (settings or self.settings).optimizer
        if rule == "auto":
            sensors = sum(1 for c in terms if c.kind == "sensor")
            rule = ("adam" if deadline else "adam-carry") if sensors >= FULL_SET else "sgd"
        return rule

    def _update(self, rule: str, s: OptimizerSettings) -> LatentUpdate:
        if rule == "sgd":
            return LatentUpdate("sgd", s.step_size, s.momentum)
        return LatentUpdate(rule, s.lr, state=self._carry if rule == "adam-carry" else None)

    # -- solving ---------------------------------------------------------------------
    def solve(
        self,
        start: torch.Tensor,
        constraints: Sequence["Constraint"],
        ctx: FrameContext,
        settings: OptimizerSettings | None = None,
    ) -> Solution:
        """Optimise from latent ``start (L,)`` against the enabled ``constraints``, each
        weighted by its ``weight`` times its :meth:`~Constraint.activity` at ``ctx.frame``,
        under ``settings`` (default: the optimizer's)."""
        s = settings or self.settings
        active, weights = active_weights(constraints, ctx.frame)
        warnings: list[str] = []
        timings = SolveTimings()
        z0 = start.detach().numpy().astype(np.float32)
        with one_blas_thread():  # tiny products: one thread is fastest
            obj = self.objective(active, weights, ctx)
            values = obj.evaluate(z0, timings)
            bad = {n for n, v in zip(obj.names, values) if not math.isfinite(v)}
            if bad:
                warnings.append(f"non-finite loss ignored this frame: {', '.join(sorted(bad))}")
                keep = [i for i, c in enumerate(active) if c.name not in bad]
                active, weights = [active[i] for i in keep], [weights[i] for i in keep]
                obj = self.objective(active, weights, ctx)
            return self._run(obj, z0, active, s, ctx, warnings, timings, None if bad else values)

    def _run(
        self,
        obj: Objective,
        z0: np.ndarray,
        active: list,
        s: OptimizerSettings,
        ctx: FrameContext,
        warnings: list[str],
        timings: SolveTimings,
        first: np.ndarray | None = None,
    ) -> Solution:
        """The solve loop: evaluate, record, stop or step (module doc). ``first``: the
        losses ``obj`` has just evaluated at ``z0`` (the loop starts from that evaluation)."""
        clock = time.perf_counter
        rule = self.update_rule(active, ctx.deadline is not None, s)
        upd = self._update(rule, s)
        stopping = StoppingRule(s.steps_cap(), s.mode == "offline", s.patience, s.min_improvement)
        timings.fast = obj.fast
        z, losses, path = z0.copy(), [], []
        deadline, cut, t_loop, steps = ctx.deadline, False, clock(), 0
        if first is None:
            timings.decoder = timings.fk_losses = 0.0  # an evaluation of another objective
        while True:
            if first is not None:
                values, first = first, None
            else:
                values = obj.evaluate(z, timings, not stopping.last(steps))
            total = float(obj.weights @ values)
            path.append(z)
            record = dict(zip(obj.names, values.tolist()))
            record["total"] = total
            losses.append(record)
            if not math.isfinite(total) or not np.isfinite(z).all():
                return self._fall_back(z0, ctx, losses, steps, warnings, "loss became non-finite", timings)
            if steps == 0:
                t_loop = clock()  # steps are timed from the first evaluation on
            elif deadline is not None and steps < stopping.cap and _past(deadline, t_loop, steps):
                cut = True
                break
            if stopping.stop_one(total, obj.satisfied, steps):
                break
            t0 = clock()
            grad = obj.gradient()
            t1 = clock()
            z = upd.step(z, grad)
            timings.backward += t1 - t0
            timings.step += clock() - t1
            steps += 1
        timings.iterations = steps
        _to_ms(timings)
        if losses[-1]["total"] > s.divergence_factor * losses[0]["total"] + 1e-6:
            return self._fall_back(z0, ctx, losses, steps, warnings, "loss diverged", timings)
        # moments from before a stretch under another rule (a tracker was lost) describe
        # a different problem: start them afresh
        self._carry = upd.state if rule == "adam-carry" else {}
        latent = torch.from_numpy(z.copy())
        return Solution(
            latent, obj.state(latent), losses, steps, warnings, timings=timings, cut=cut, path=np.stack(path)
        )

    def _fall_back(
        self,
        z0: np.ndarray,
        ctx: FrameContext,
        losses: list[dict[str, float]],
        steps: int,
        warnings: list[str],
        why: str,
        timings: SolveTimings,
    ) -> Solution:
        warnings.append(f"{why}; frame kept its starting latent")
        z = torch.from_numpy(z0.copy())
        with torch.no_grad():
            state = self.decode(z, ctx)
        return Solution(z, state.detached(), losses, steps, warnings, fell_back=True, timings=timings)


def _root_frames(ctx: FrameContext) -> RootFrames:
    """The chain's root for one frame (:class:`RootFrames` with ``A = 1``)."""
    n = lambda t: t.detach().double().numpy()  # noqa: E731
    ov, anchor = ctx.root_override, ctx.root_anchor
    # the exact type first: the protocol's isinstance costs ~10 us a frame
    if anchor is not None and not (type(anchor) is RootAnchor or isinstance(anchor, JointAnchor)):
        raise TypeError(
            f"FrameContext.root_anchor: the fast objective places the body by a joint anchor "
            f"(joint, position), not by {type(anchor).__name__}; solve it with PoseOptimizer(fast=False)"
        )
    return RootFrames(
        heading=QN.to_matrix(Q.heading(n(ctx.previous_root.rotation)))[None],
        previous=n(ctx.previous_root.position)[None],
        position=None if ov is None else n(ov.position)[None],
        rotation=None if ov is None or ov.rotation is None else QN.to_matrix(n(ov.rotation))[None],
        anchor=None if anchor is None else anchor.joint,
        anchor_position=None if anchor is None else n(anchor.position)[None],
    )


def _fast_state(latent: torch.Tensor, obj: FastObjective, ctx: FrameContext) -> PoseState:
    """The fast objective's last evaluated pose as a (detached, float32) :class:`PoseState`."""
    local = obj.chain.local()[0].copy()
    n = lambda t: t.detach().double().numpy()  # noqa: E731
    ov = ctx.root_override
    rotation = None if ov is None or ov.rotation is None else n(ov.rotation)
    local[0], _ = place_root(Q.heading(n(ctx.previous_root.rotation)), local[0], rotation=rotation)
    f = lambda a: torch.as_tensor(a, dtype=torch.float32)  # noqa: E731
    return PoseState(
        f(obj.P[0]), None, f(local), latent, ctx.previous_positions, ctx.frame, ctx.prediction, f(obj.W[0])
    )


def _past(deadline: float, t_loop: float, steps: int) -> bool:
    """Whether one more step, at the mean time of the ``steps`` taken since ``t_loop``,
    would end after ``deadline`` (all ``time.perf_counter`` seconds)."""
    now = time.perf_counter()
    return now + (now - t_loop) / steps > deadline


def _to_ms(t: SolveTimings) -> None:
    for k in ("decoder", "fk_losses", "backward", "step"):
        setattr(t, k, 1000.0 * getattr(t, k))
