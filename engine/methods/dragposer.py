"""DragPoser (Ponton et al. 2024): full-body pose by latent-space optimisation.

Every frame, each sensor reading becomes (or updates) a ``sensor`` constraint named
``sensor:<joint>`` (enabled while connected, weighted by :meth:`set_sensor_weight`),
the temporal predictor proposes a latent (:mod:`engine.solver.temporal`), and
:class:`engine.solver.PoseOptimizer` moves the latent until the sensors, the
temporal prior and the user's constraints agree. This module holds the per-frame
step (a :class:`~engine.methods.dragposer_parts.FramePlan` read from the frame, the
solve, the exact after-solve steps, the frame's history) and the registry factory
:func:`create`. Its collaborators, one job each: the trackers as terms, the user's
constraints and the prior's source (:mod:`engine.methods.dragposer_parts`), the caller's
edits between frames and the settings a frame runs with
(:mod:`engine.methods.dragposer_edits`), where the body is and which way it faces
(:mod:`engine.methods.dragposer_root`).
"""

from __future__ import annotations

import dataclasses
import time
from collections.abc import Iterable, Sequence
from typing import Any

import numpy as np
import torch

from engine import skeleton as sk
from engine.constraints import Constraint, GroundConstraint, SensorConstraint, SmoothConstraint, TemporalPriorConstraint
from engine.constraints.gait import GaitConstraint
from engine.constraints.sensor import unit_rotation
from engine.errors import UserError
from engine.kinematics import quaternion as Q
from engine.methods import dragposer_root as roots
from engine.methods.base import FrameResult, Method
from engine.methods.dragposer_edits import CallerEdits, FrameSettings
from engine.methods.dragposer_parts import FramePlan, TrackerTerms, UserConstraints, smoothing_history
from engine.methods.dragposer_prior import PriorSource
from engine.methods.solve_record import SolveRecord, record_of
from engine.models.heading import default_heading_model
from engine.models.stance import default_stance_model
from engine.motion.clip import Motion
from engine.sensors import SensorFrame
from engine.solver import FrameContext, LatentDecoder, LatentPredictor, OptimizerSettings, PoseOptimizer, RootFrame
from engine.solver.gait import GaitPlanner
from engine.solver.limb_ik import CLAVICLES
from engine.solver.tracker_net import TrackerNets, default_tracker_nets
from engine.solver.tracker_prior import PoseBank, combination, default_bank
from engine.startup_trace import mark


class DragPoserMethod(CallerEdits, Method):
    """Latent-space pose optimisation guided by a temporal predictor.

    Parameters
    ----------
    decoder : LatentDecoder
        Frozen pose decoder (``PoseVAE`` or a stand-in with ``decode``).
    predictor : LatentPredictor, optional
        Temporal predictor; without it there is no temporal prior.
    settings : OptimizerSettings, optional
    latent_dim : int
        Size of the latent (24 in DragPoser).
    fast : bool
        Let the solver take its fast path (hand-derived gradients) when it can; False
        forces the autograd reference path (same results, slower; for tests).
    **overrides
        Settings fields (``mode``, ``iterations``, ``lr``...) applied on top.
    """

    name = "dragposer"
    takes_deadline = True

    def __init__(
        self,
        decoder: LatentDecoder,
        predictor: LatentPredictor | None = None,
        settings: OptimizerSettings | None = None,
        latent_dim: int = 24,
        fast: bool = True,
        bank: PoseBank | None = None,
        nets: TrackerNets | None = None,
        **overrides: Any,
    ) -> None:
        self.decoder = decoder
        if isinstance(decoder, torch.nn.Module):
            decoder.eval().requires_grad_(False)
        if isinstance(predictor, torch.nn.Module):
            predictor.eval().requires_grad_(False)
        self.predictor = predictor
        self.bank = bank  # the tracker prior's training poses (engine/solver/tracker_prior.py)
        self.nets = nets  # the tracker prior's networks (engine/solver/tracker_net.py)
        self._settings = FrameSettings(settings)
        self.settings = self._settings.settings
        self.latent_dim = latent_dim
        self.fast = fast
        self._user = UserConstraints()
        self._weights: dict[str, float] = {}  # tracker weights by joint, kept across clips
        self._bank_later: tuple[tuple[str, ...], ...] = ()
        self.configure(**overrides)
        self.reset(sk.Skeleton.canonical())

    @property
    def sensors(self) -> dict[str, SensorConstraint]:
        """This clip's tracker terms by joint name."""
        return self.trackers.constraints

    # -- running ---------------------------------------------------------------------

    def reset(self, skeleton: sk.Skeleton, fps: float = sk.FPS, *, reference: Motion | None = None) -> None:
        self.skeleton = skeleton
        self.fps = fps
        self.optimizer = PoseOptimizer(self.decoder, skeleton.offsets, self.settings, fast=self.fast)
        self.trackers = TrackerTerms(self._weights, heading=default_heading_model())
        self.priors = PriorSource(self.predictor, self.bank, self.settings, self.nets)
        self.priors.bank_later = self._bank_later
        self.prior = TemporalPriorConstraint(name="temporal_prior")
        self.smooth = SmoothConstraint(name="smooth")
        self.ground = GroundConstraint(name="ground")
        self.gait = GaitConstraint(name="gait")
        self.gait_planner = GaitPlanner(
            fps, stance=default_stance_model()
        )  # the gait term's targets (engine/solver/gait.py)
        self._settings.forget()
        self._frame = 0
        self._latent = torch.zeros(self.latent_dim)
        self._root: RootFrame | None = None
        self._positions: torch.Tensor | None = None  # float32 (22, 3), the solver's view
        self._pos64: np.ndarray | None = None  # the same values in float64 (numpy users)
        self._before64: np.ndarray | None = None
        self._last: FrameResult | None = None
        self._roots: list[tuple[torch.Tensor, torch.Tensor, torch.Tensor]] = []  # see _advance
        self.last_solve: SolveRecord | None = None  # the last frame's solve (latent debugging)

    def step(self, sensors: SensorFrame, deadline: float | None = None) -> FrameResult:
        """Solve the next frame. ``deadline`` (a ``time.perf_counter()`` time; live input)
        stops the solve's iterations early enough to end by then (at least one step;
        engine/solver/optimizer.py), the first frame's (solved offline, to convergence
        otherwise) too; the result's ``iterations`` says how many ran."""
        threads = torch.get_num_threads()
        if self.settings.threads:
            torch.set_num_threads(self.settings.threads)
        try:
            return self._step(sensors, deadline)
        finally:
            torch.set_num_threads(threads)

    def plan(self, frame: SensorFrame, term: bool = True) -> FramePlan:
        """Take a frame's readings and say what it will be solved against (the trackers'
        term, the settings, the pose bank's lookup input, the after-solve targets); the
        next :meth:`step` or the batched offline solve solves it. ``term`` False leaves
        the trackers' term out (:attr:`FramePlan.trackers` None): :meth:`step` solves
        against the sensor constraints and would build it for nothing."""
        warnings = self.trackers.update(frame, self.settings, self.fps, self._pos64)
        live = tuple(j for j, c in self.sensors.items() if c.enabled)
        hip = self.sensors.get("root")
        s = self._settings.for_sensors(live, hip is None or hip.dof == 6)
        base = self.settings.sensor_rotation_weight
        if s.sensor_rotation_weight != base and base > 0:  # the profile's rotation weight (blend kept)
            self.trackers.scale_rotation_weights(s.sensor_rotation_weight / base)
        trackers, names, weights = self.trackers.term(build=term)
        hip_pose = None
        if hip is not None and hip.enabled and hip.dof == 6:
            hip_pose = (np.array(hip.position, dtype=np.float64), unit_rotation(hip.rotation))
        held = self._user.held_joints()
        return FramePlan(
            settings=s,
            warnings=warnings,
            trackers=trackers,
            names=names,
            weights=weights,
            bank_readings=self.priors.readings(s, self.trackers.history),
            feet=self.trackers.feet(),
            hip=hip_pose,
            reach={
                k: np.array(v, dtype=np.float64)
                for k, v in {
                    **(self.trackers.head_target(held) if s.head_reach else {}),
                    **(self.trackers.reach_targets(held) if s.reach else {}),
                }.items()
            },
            turn={k: np.array(v, dtype=np.float64) for k, v in self.trackers.rotation_targets().items()}
            if s.sensor_rotations
            else {},
            level=self.trackers.level_ankles(held) if s.level_feet else (),
            shoulder_deg=0.0 if held & CLAVICLES else float(s.shoulder_reach),
        )

    def solve_clip(self, frames: Sequence[SensorFrame]) -> list[FrameResult] | None:
        """Offline mode: the whole clip solved in windows of frames optimised together
        (:mod:`engine.methods.dragposer_batch`), or None when this clip is solved frame by
        frame (realtime mode, user constraints, no 6-DoF hip tracker in every frame...)."""
        from engine.methods.dragposer_batch import solve_clip

        return solve_clip(self, frames)

    def _step(self, sensors: SensorFrame, deadline: float | None = None) -> FrameResult:
        t0 = time.perf_counter()
        plan = self.plan(sensors, term=False)
        warnings, s = plan.warnings, plan.settings
        override = roots.root_override(self.sensors)
        if self._root is None:
            self._root = roots.initial_root(self.skeleton, self.sensors, self.trackers.facing)
        prediction, prior_weight, warned = self.priors.latent(self._frame, s, plan.bank_readings)
        warnings += warned
        start = prediction if prediction is not None and s.init_from_prediction else self._latent
        self.prior.weight = prior_weight
        self.smooth.weight, self.ground.weight = plan.smooth_weight, plan.ground_weight
        self.smooth.set_history(*smoothing_history(self._frame, self._pos64, self._before64))
        anchor = roots.root_anchor(self.sensors, self.settings) if override is None else None
        if override is None and anchor is None and s.root_anchor != "none" and self._frame > 0:
            override = roots.held_root(self._root, self.trackers.points, self.trackers.last_points)
        root = roots.reference_root(
            self._root, self.sensors, s, override, self.trackers.facing, self.fps, self.trackers.learned_facing
        )
        # the clip's frame, not the count of solves since the reset: a constraint limited
        # to frames acts by the clip's frame numbers (the studio resets on a seek)
        ctx = FrameContext(root, override, anchor, self._positions, prediction, sensors.frame, deadline)
        self.settle_constraints(self._pos64)  # e.g. an unset pin takes the previous pose
        terms = [
            *self.sensors.values(),
            self.prior,
            self.smooth,
            self.ground,
            *self._gait_terms(plan),
            *self.constraints,
        ]
        # frame 0 has no history to start from: it is solved offline
        sol = self.optimizer.solve(start, terms, ctx, dataclasses.replace(s, mode="offline") if self._frame == 0 else s)
        warnings += sol.warnings
        previous = None if self._frame == 0 or self.last_solve is None else self.last_solve.context.frame
        self.last_solve = record_of(sol, ctx, terms, start is prediction, self.priors.from_bank, previous)
        state = sol.state
        if not (torch.isfinite(state.positions).all() and torch.isfinite(state.local_rot).all()):
            warnings.append("decoded pose is not finite; previous pose repeated")
            return self._repeat_last(warnings, sol.losses, sol.iterations, t0)
        local_rot, positions = state.local_rot.double().numpy(), state.positions.double().numpy()
        local_rot, positions = plan.finished(local_rot, positions, self.skeleton.offsets)
        self._advance(sol.latent, root, local_rot[0], positions)
        result = FrameResult(
            local_rot=local_rot,
            root_pos=positions[0].copy(),
            positions=positions,
            iterations=sol.iterations,
            losses=sol.losses,
            latent=sol.latent.double().numpy(),
            ms=1000.0 * (time.perf_counter() - t0),
            warnings=warnings,
            timings=sol.timings.per_iteration() if sol.iterations else {},
        )
        self._last = result
        return result

    def prepare_bank_later(self, combinations: Iterable[tuple[str, ...]]) -> None:
        """Have :meth:`between_frames` prepare the pose bank (its tables and these
        combinations, :meth:`PoseBank.prepare`) after the next frame instead of now."""
        self._bank_later = self.priors.bank_later = tuple(combinations)

    def between_frames(self) -> None:
        """The prior's deferred work (:meth:`PriorSource.between_frames`): the same latents
        as when the next :meth:`step` does it, without adding to that frame's latency.
        Runs with the solver's torch thread count, as :meth:`step` does."""
        threads = torch.get_num_threads()
        if self.settings.threads:
            torch.set_num_threads(self.settings.threads)
        try:
            self.priors.between_frames()
            self._bank_later = self.priors.bank_later
        finally:
            torch.set_num_threads(threads)

    def decode_latent(self, latent: np.ndarray) -> np.ndarray:
        """World joint positions ``(22, 3)`` of ``latent (L,)``, placed at the current root."""
        z = torch.as_tensor(np.asarray(latent, dtype=np.float32).reshape(self.latent_dim))
        root = self._root or roots.initial_root(self.skeleton, self.sensors, self.trackers.facing)
        with torch.no_grad():
            state = self.optimizer.decode(z, FrameContext(root))
        return state.positions.double().numpy()

    # -- internals -------------------------------------------------------------------

    def _gait_terms(self, plan: FramePlan) -> list[Constraint]:
        """The gait term with this frame's targets from the hips' (else the head's) tracker
        travel: the planned steps (``gait_weight``) and the standing legs (``stand_weight``),
        or nothing while both weights are 0 (the solve is then as without it)."""
        walk, stand = plan.gait_weight, plan.stand_weight
        weight = walk if walk > 0.0 else stand
        if weight <= 0.0:
            self.gait_planner.reset()
            return []
        anchor = next(
            (c.position for j in ("root", "upperneck") if (c := self.sensors.get(j)) is not None and c.enabled), None
        )
        hands = [c.position for j in ("lwrist", "rwrist") if (c := self.sensors.get(j)) is not None and c.enabled]
        head = c.position if (c := self.sensors.get("upperneck")) is not None and c.enabled else None
        self.gait.set_targets(
            self.gait_planner.update(
                anchor,
                self._pos64,
                np.array(hands) if len(hands) == 2 else None,
                head,
                walk=walk > 0.0,
                stand=stand / weight,
                distance=self.priors.distance,
            )
        )
        self.gait.weight = weight
        return [self.gait]

    def _advance(self, latent: torch.Tensor, prev: RootFrame, root_rot: np.ndarray, positions: np.ndarray) -> None:
        """Keep the solved frame as the next frame's history, in float32 as the solver's
        tensors are (the root increment stays in torch float32: the predictor's
        conditioning, and so every later frame, depends on its exact rounding)."""
        rot32, pos32 = np.asarray(root_rot, dtype=np.float32), np.asarray(positions, dtype=np.float32)
        rot_t, pos_t = torch.from_numpy(rot32), torch.from_numpy(pos32)
        # the predictor's conditioning, computed only if the predictor runs on it (never while
        # the pose bank gives the prior): the same torch operations on the same tensors
        self._roots.append((prev.rotation, prev.position, pos_t[0]))
        del self._roots[: -self.settings.predictor_every]
        self.priors.schedule.record(self._frame, latent, roots.Conditioning(tuple(self._roots), pos_t))
        self._latent = latent
        self._root = RootFrame(rot_t, pos_t[0].clone())
        self._before64 = self._pos64
        self._positions, self._pos64 = pos_t, pos32.astype(np.float64)
        self._frame += 1

    def _repeat_last(self, warnings: list[str], losses: list, iterations: int, t0: float) -> FrameResult:
        if self._last is not None:
            res = dataclasses.replace(self._last, losses=losses, iterations=iterations, warnings=warnings)
        else:
            local = Q.identity((sk.NUM_JOINTS,))
            root = self._root.position.double().numpy() if self._root else np.zeros(3)
            from engine.kinematics.fk import fk

            pos, _ = fk(local, root, self.skeleton.offsets)
            res = FrameResult(local, root, pos, iterations, losses, self._latent.double().numpy(), 0.0, warnings)
        self._frame += 1
        res.ms = 1000.0 * (time.perf_counter() - t0)
        return res


def create(
    mode: str = "realtime",
    iterations: int | None = None,
    lr: float | None = None,
    vae_path: Any = None,
    predictor_path: Any = None,
    prepare_bank: bool = True,
    **overrides: Any,
) -> DragPoserMethod:
    """Registry factory: DragPoser with the shipped models (``engine.models``), or with a
    user-trained VAE (``vae_path``) and, optionally, its predictor (``predictor_path``).

    ``prepare_bank`` builds the pose bank's two anchor tables and the shipped presets'
    combinations now (about 1.3 CPU s beyond the first frame's own table and combination),
    so that no live frame waits for them. False leaves them: the first frame's lookup
    builds the table and combination it needs, and :meth:`DragPoserMethod.between_frames`
    the rest after that frame (the studio, which shows one frame and then waits for the
    user). The lookups are the same either way.

    Raises
    ------
    UserError
        When the models cannot be loaded (the message says why).
    """
    from engine.models import load_default_models, load_models

    if vae_path is not None:
        models = load_models(vae_path, predictor_path)
    elif predictor_path is not None:
        raise UserError("a predictor path needs the VAE it was trained on (vae_path)")
    else:
        models = load_default_models()
    mark("engine: models loaded")
    decoder, predictor = models.vae, models.predictor
    # the shipped pose bank holds the shipped VAE's latents: another VAE goes without it
    bank = default_bank(vae_path)
    if bank is not None and prepare_bank:  # the presets' lookups ready before their first frame (no cold start)
        bank.prepare(preset_combinations())
    mark("engine: pose bank ready")
    values: dict[str, Any] = {"mode": mode, **overrides}
    if iterations is not None:
        values["iterations" if mode == "realtime" else "max_iterations"] = iterations
    if lr is not None:
        values["lr"] = lr
    nets = default_tracker_nets(vae_path) if bank is not None else None
    method = DragPoserMethod(decoder, predictor, latent_dim=decoder.config.latent, bank=bank, nets=nets, **values)
    if bank is not None and not prepare_bank:
        method.prepare_bank_later(preset_combinations())
    return method


def preset_combinations() -> list[tuple[str, ...]]:
    """The pose-bank combinations (:func:`engine.solver.tracker_prior.combination`) of the
    shipped sensor presets' 6-DoF trackers."""
    from engine.tracking.presets import PRESET_SENSORS

    combos = (combination(s.joint for s in sensors if s.dof == 6) for sensors in PRESET_SENSORS.values())
    return list(dict.fromkeys(c for c in combos if c is not None))
