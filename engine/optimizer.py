"""DragPoser's pose optimizer: Adam on the latent through a frozen decoder (Ponton et al.
2024, sec. 4.4 and Algorithm 1).

Per frame, the latent ``z (L,)`` starts from the temporal predictor's latent (or the
previous frame's), is decoded to a world pose (:mod:`engine.optimizer_pose`: forward
kinematics plus the root handling described there), and is moved by Adam against
``sum(weight_k * loss_k)`` over the enabled constraints (sensors, the temporal prior and
any user constraint). Two modes:

* ``realtime``: exactly ``iterations`` steps per frame;
* ``offline``: step until every constraint reports :meth:`~Constraint.satisfied` (the
  sensors' position and rotation tolerances), the loss stops improving, or
  ``max_iterations`` is reached.

Robustness: a constraint whose loss is NaN/inf at the starting latent is left out of
this frame's solve (with a warning); a loss or latent that becomes non-finite, or a
final loss far above the starting one (divergence), makes the frame fall back to its
starting latent, again with a warning. The caller's state is only ever updated from a
finite solution, so the next frame starts clean.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Protocol

import numpy as np
import torch

from engine import skeleton as sk
from engine.constraints.base import Constraint, PoseState
from engine.errors import UserError
from engine.optimizer_pose import DecodedPose, LevelFK, RootAnchor, RootFrame, RootOverride, world_root

MODES = ("realtime", "offline")
#: Latent update rules: plain gradient steps (DragPoser eq. in sec. 4.4), Adam restarted every
#: frame, or Adam whose moment estimates carry over from frame to frame.
OPTIMIZERS = ("auto", "sgd", "adam", "adam-carry")
#: Connected sensors from which ``auto`` uses Adam (and the predictor looks one step ahead).
FULL_SET = 6


class LatentDecoder(Protocol):
    """What the optimizer needs from the pose VAE (``engine.models.PoseVAE`` fits)."""

    def decode(self, z: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor]:
        """``z (B, L)`` -> unit quaternions ``rot (B, 22, 4)`` and ``disp (B, 3)`` metres."""
        ...


@dataclass
class OptimizerSettings:
    """Parameters of the pose optimizer; a change applies from the next frame.

    Attributes
    ----------
    mode : str
        ``realtime`` (fixed ``iterations``) or ``offline`` (until tolerances are met).
    iterations : int
        Adam steps per frame in realtime mode.
    max_iterations : int
        Cap on Adam steps per frame in offline mode.
    lr : float
        Adam learning rate (latent units per step, roughly).
    optimizer : str
        Latent update rule: ``sgd`` (plain gradient steps of ``step_size``, the paper's
        update), ``adam`` (restarted every frame), ``adam-carry`` (moments kept across
        frames) or ``auto``: ``adam-carry`` with six or more connected sensors, plain
        steps with fewer (Adam moves every latent dimension by about ``lr`` per step, so
        with few trackers the unconstrained body parts wander; see docs/optimizer.md).
    step_size : float
        Step of the ``sgd`` rule: ``z -= step_size * gradient``.
    momentum : float
        Nesterov momentum of the ``sgd`` rule within a frame (0 = none).
    position_tolerance : float
        Metres; a sensor is satisfied when its position error is below it (offline).
    rotation_tolerance : float
        Degrees; same for the rotation of a 6-DoF sensor.
    sensor_rotation_weight : float
        Weight of a sensor's rotation term (``sin^2(angle/2)``) against its squared
        position error (m^2).
    temporal_weight : float
        Weight of the temporal prior (MSE to the predictor's latent).
    init_from_prediction : bool
        Start each frame from the predictor's latent when there is one. Off by default:
        Algorithm 1 starts from the previous frame's latent and uses the prediction only
        through the temporal prior, and with the shipped predictor starting from its
        latent measured 5-18 cm worse (6 sensors, realtime, two validation clips).
    future_window : int
        Predictor steps per run (W_f); 0 picks DragPoser's defaults: 1 with six or more
        connected sensors, 16 with fewer.
    past_window : int
        Past latents the predictor sees (W_p).
    predictor_every : int
        The predictor runs every this many frames (n).
    patience : int
        Offline: stop after this many steps without a relative improvement of
        ``min_improvement`` in the total loss.
    min_improvement : float
        Relative improvement that counts as progress (offline).
    divergence_factor : float
        A final loss above ``divergence_factor`` times the starting loss (plus 1e-6)
        counts as divergence; the frame falls back to its starting latent.
    root_anchor : str
        Without a connected hip tracker, the joint whose tracker places the body
        (``upperneck``, the head, by default; any joint name), or ``none`` to integrate
        the decoded root displacement from frame to frame (drifts without a hip tracker:
        tens of centimetres over a clip with head and hands only).
    sensor_blend : float
        Seconds over which a tracker that disconnects or reconnects is blended out / in
        (``engine/methods/sensor_blend.py``); 0 = the target jumps. Trackers that place
        the body (hips, ``root_anchor``) are never blended.
    threads : int
        Torch intra-op threads while solving (0 = leave torch's setting). The tensors
        are tiny, so one thread is fastest; on a busy 2-core machine, torch's default
        made a frame with the real-size VAE about 20x slower in our measurements.
    """

    mode: str = "realtime"
    iterations: int = 10
    max_iterations: int = 100
    lr: float = 0.05
    position_tolerance: float = 0.01
    rotation_tolerance: float = 5.0
    sensor_rotation_weight: float = 0.1
    temporal_weight: float = 0.01
    init_from_prediction: bool = False
    future_window: int = 0
    past_window: int = 16
    predictor_every: int = 4
    patience: int = 10
    min_improvement: float = 1e-4
    divergence_factor: float = 100.0
    root_anchor: str = "upperneck"
    optimizer: str = "auto"
    step_size: float = 0.3
    momentum: float = 0.0
    threads: int = 1
    sensor_blend: float = 0.0

    def __post_init__(self) -> None:
        self.validate()

    def validate(self) -> None:
        """Raise :class:`UserError` naming the first bad field."""
        if self.mode not in MODES:
            raise UserError(f"optimizer setting 'mode' must be one of {', '.join(MODES)}, got {self.mode!r}")
        ints = ("iterations", "max_iterations", "future_window", "past_window", "predictor_every", "patience",
                "threads")
        for name in ints:
            v = getattr(self, name)
            if isinstance(v, bool) or not isinstance(v, (int, np.integer)) or v < (0 if name in ("future_window", "threads") else 1):
                raise UserError(f"optimizer setting {name!r} must be a positive integer, got {v!r}")
            setattr(self, name, int(v))
        floats = ("lr", "position_tolerance", "rotation_tolerance", "sensor_rotation_weight", "temporal_weight",
                  "min_improvement", "divergence_factor", "momentum", "step_size", "sensor_blend")  # fmt: skip
        for name in floats:
            v = getattr(self, name)
            if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v) or v < 0:
                raise UserError(f"optimizer setting {name!r} must be a finite number >= 0, got {v!r}")
            setattr(self, name, float(v))
        if self.optimizer not in OPTIMIZERS:
            raise UserError(f"optimizer setting 'optimizer' must be one of {', '.join(OPTIMIZERS)}, got {self.optimizer!r}")
        if self.root_anchor != "none" and self.root_anchor not in sk.JOINT_INDEX:
            raise UserError(f"optimizer setting 'root_anchor' must be a joint name or 'none', got {self.root_anchor!r}")
        if self.momentum >= 1:
            raise UserError(f"optimizer setting 'momentum' must be below 1, got {self.momentum!r}")
        if self.lr <= 0:
            raise UserError("optimizer setting 'lr' must be > 0")
        if self.step_size <= 0:
            raise UserError("optimizer setting 'step_size' must be > 0")

    def steps_cap(self) -> int:
        return self.iterations if self.mode == "realtime" else self.max_iterations


@dataclass
class FrameContext:
    """Everything about a frame the decoded pose depends on besides the latent.

    Attributes
    ----------
    previous_root : RootFrame
        The previous frame's solved root (heading and position reference).
    root_override : RootOverride or None
        Connected hip sensor, which dictates the root.
    root_anchor : RootAnchor or None
        Without a hip sensor: the joint (head) whose tracker places the body.
    previous_positions : Tensor (22, 3) or None
        Previous frame's solved joint positions, metres.
    prediction : Tensor (L,) or None
        Temporal predictor's latent for this frame.
    frame : int
        Frame index.
    """

    previous_root: RootFrame
    root_override: RootOverride | None = None
    root_anchor: RootAnchor | None = None
    previous_positions: torch.Tensor | None = None
    prediction: torch.Tensor | None = None
    frame: int = 0


@dataclass
class Solution:
    """Result of one frame's optimisation (all detached).

    Attributes
    ----------
    latent : Tensor (L,)
    state : PoseState
        Decoded pose of ``latent``.
    losses : list of dict
        ``losses[k]`` = every term (by constraint name) and ``"total"`` at the latent
        after ``k`` steps; ``len(losses) == iterations + 1``.
    iterations : int
        Adam steps taken.
    warnings : list of str
    fell_back : bool
        True when the solve was abandoned for the starting latent.
    """

    latent: torch.Tensor
    state: PoseState
    losses: list[dict[str, float]] = field(default_factory=list)
    iterations: int = 0
    warnings: list[str] = field(default_factory=list)
    fell_back: bool = False


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
    """

    def __init__(self, decoder: LatentDecoder, offsets: np.ndarray, settings: OptimizerSettings | None = None):
        self.decoder = decoder
        if isinstance(decoder, torch.nn.Module):  # frozen: no gradients for its weights
            decoder.eval().requires_grad_(False)
        self.settings = settings or OptimizerSettings()
        self.fk = LevelFK(offsets)
        self._carry: dict = {}

    def decode(self, z: torch.Tensor, ctx: FrameContext) -> DecodedPose:
        """World pose of latent ``z (L,)`` in the context of a frame (differentiable)."""
        rot, disp = self.decoder.decode(z[None])
        rot, disp = rot[0], disp[0]
        root_rot, root_pos = world_root(rot[0], disp, ctx.previous_root, ctx.root_override)
        local = torch.cat((root_rot[None], rot[1:]), dim=0)
        pos, mats = self.fk.matrices(local, root_pos)
        if ctx.root_anchor is not None and ctx.root_override is None:
            pos = ctx.root_anchor.apply(pos)
        return DecodedPose(self.fk, pos, mats, local, z, ctx.previous_positions, ctx.frame, ctx.prediction)

    def _evaluate(self, terms: Sequence[Constraint], state: PoseState) -> torch.Tensor:
        return torch.stack([c.loss(state).reshape(()) for c in terms]) if terms else state.latent.new_zeros(0)

    def _evaluator(self, terms: list[Constraint], like: torch.Tensor):
        """Reorder ``terms`` so kinds with a :meth:`~Constraint.batch` fast path come first,
        and return them with a function ``state -> (K,)`` losses in that order."""
        kinds: dict[type, list[Constraint]] = {}
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
                parts.append(self._evaluate(singles, state))
            return torch.cat(parts) if parts else like.new_zeros(0)

        return ordered + singles, evaluate

    def solve(self, start: torch.Tensor, constraints: Sequence[Constraint], ctx: FrameContext) -> Solution:
        """Optimise from latent ``start (L,)`` against the enabled ``constraints``."""
        s = self.settings
        warnings: list[str] = []
        terms = [c for c in constraints if c.enabled and c.weight > 0]
        z = start.detach().clone().requires_grad_(True)
        state = self.decode(z, ctx)
        values = self._evaluate(terms, state)
        finite = torch.isfinite(values).tolist()
        if not all(finite):
            bad = [c.name for c, ok in zip(terms, finite) if not ok]
            warnings.append(f"non-finite loss ignored this frame: {', '.join(bad)}")
            terms = [c for c, ok in zip(terms, finite) if ok]
            values = values[torch.tensor(finite, dtype=torch.bool)]
        terms, evaluate = self._evaluator(terms, values)
        values = evaluate(state)
        names = [c.name for c in terms]
        weights = torch.tensor([c.weight for c in terms], dtype=values.dtype)
        rule = self.update_rule(terms)
        opt = self._make_optimizer(z, rule)
        losses: list[dict[str, float]] = []
        cap, offline = s.steps_cap(), s.mode == "offline"
        best, since_best, steps = math.inf, 0, 0
        while True:
            total = (weights * values).sum()
            row = values.detach().tolist()
            losses.append({**dict(zip(names, row)), "total": float(total.detach())})
            if not math.isfinite(losses[-1]["total"]) or not bool(torch.isfinite(z).all()):
                return self._fall_back(start, ctx, losses, steps, warnings, "loss became non-finite")
            if steps >= cap:
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
            opt.zero_grad(set_to_none=True)
            total.backward()
            opt.step()
            steps += 1
            state = self.decode(z, ctx) if steps < cap or offline else None
            if state is None:  # realtime: last step, evaluate without a graph
                with torch.no_grad():
                    state = self.decode(z, ctx)
            values = evaluate(state)
        if losses[-1]["total"] > s.divergence_factor * losses[0]["total"] + 1e-6:
            return self._fall_back(start, ctx, losses, steps, warnings, "loss diverged")
        final = z.detach().clone()
        # moments from before a stretch under another rule (a tracker was lost) describe
        # a different problem: start them afresh
        self._carry = ({k: (v.detach().clone() if torch.is_tensor(v) else v) for k, v in opt.state[z].items()}
                       if rule == "adam-carry" else {})  # fmt: skip
        return Solution(final, _detached(state, final), losses, steps, warnings)

    def update_rule(self, terms: Sequence[Constraint]) -> str:
        """The rule ``solve`` uses with these enabled ``terms``: ``auto`` is Adam with
        carried moments with at least :data:`FULL_SET` sensors, plain gradient steps with
        fewer."""
        rule = self.settings.optimizer
        if rule == "auto":
            sensors = sum(1 for c in terms if getattr(c, "kind", "") == "sensor")
            rule = "adam-carry" if sensors >= FULL_SET else "sgd"
        return rule

    def _make_optimizer(self, z: torch.Tensor, rule: str) -> torch.optim.Optimizer:
        s = self.settings
        if rule == "sgd":
            return torch.optim.SGD([z], lr=s.step_size, momentum=s.momentum, nesterov=s.momentum > 0)
        opt = torch.optim.Adam([z], lr=s.lr)
        if rule == "adam-carry" and self._carry:
            opt.state[z] = {k: (v.clone() if torch.is_tensor(v) else v) for k, v in self._carry.items()}
        return opt

    def _fall_back(self, start: torch.Tensor, ctx: FrameContext, losses: list[dict[str, float]],
                   steps: int, warnings: list[str], why: str) -> Solution:  # fmt: skip
        warnings.append(f"{why}; frame kept its starting latent")
        z = start.detach().clone()
        with torch.no_grad():
            state = self.decode(z, ctx)
        return Solution(z, _detached(state, z), losses, steps, warnings, fell_back=True)


def _detached(state: PoseState, latent: torch.Tensor) -> PoseState:
    mats = state.rotation_matrices
    return DecodedPose(
        state._fk if isinstance(state, DecodedPose) else None,  # type: ignore[arg-type]
        state.positions.detach(), mats.detach() if mats is not None else None,
        state.local_rot.detach(), latent, state.previous_positions, state.frame, state.prediction,
    )  # fmt: skip
