"""DragPoser (Ponton et al. 2024): full-body pose by latent-space optimisation.

Every frame, each sensor reading becomes (or updates) a ``sensor`` constraint named
``sensor:<joint>`` (enabled while connected, weighted by :meth:`set_sensor_weight`),
the temporal predictor proposes a latent (:mod:`engine.solver.temporal`), and
:class:`engine.solver.PoseOptimizer` moves the latent until the sensors, the
temporal prior and the user's constraints agree. This module holds the per-frame
step (readings to terms, the solve, the exact after-solve steps, the frame's history)
and the registry factory :func:`create`. Beside it: the edits between frames (settings
with ``configure``, user constraints, tracker weights) and the settings a frame runs
with, :mod:`engine.methods.dragposer_edits`; where the body is and which way it faces,
:mod:`engine.methods.dragposer_root`.
"""

from __future__ import annotations

import dataclasses
import math
import time
from collections.abc import Iterable, Sequence
from typing import Any

import numpy as np
import torch

from engine import skeleton as sk
from engine.constraints import (
    Constraint, GroundConstraint, SensorConstraint, SmoothConstraint, TemporalPriorConstraint,
)  # fmt: skip
from engine.errors import UserError
from engine.kinematics import quaternion as Q
from engine.latent.record import SolveRecord, record_of
from engine.methods import dragposer_root as roots
from engine.methods.base import FrameResult, Method
from engine.methods.dragposer_edits import DragPoserEdits
from engine.methods.sensor_blend import SensorBlend
from engine.sensors import Sensor, SensorFrame
from engine.motion.clip import Motion
from engine.solver import (
    FrameContext, LatentDecoder, LatentPredictor, OptimizerSettings, PoseOptimizer, RootFrame, TemporalSchedule,
)  # fmt: skip
from engine.solver.limb_ik import LIMBS, finish
from engine.solver.pose import body_facing
from engine.solver.tracker_prior import PoseBank, TrackerHistory, combination, default_bank
from engine.startup_trace import mark

class DragPoserMethod(DragPoserEdits, Method):
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

    def __init__(self, decoder: LatentDecoder, predictor: LatentPredictor | None = None,
                 settings: OptimizerSettings | None = None, latent_dim: int = 24, fast: bool = True,
                 bank: PoseBank | None = None, **overrides: Any) -> None:  # fmt: skip
        self.decoder = decoder
        if isinstance(decoder, torch.nn.Module):
            decoder.eval().requires_grad_(False)
        if isinstance(predictor, torch.nn.Module):
            predictor.eval().requires_grad_(False)
        self.predictor = predictor
        self.bank = bank  # the tracker prior's training poses (engine/solver/tracker_prior.py)
        self._bank_later: tuple[tuple[str, ...], ...] = ()  # combinations between_frames prepares
        self.settings = settings or OptimizerSettings()
        # settings the caller chose (kept against the sensor-set profiles, engine/solver/profiles.py)
        defaults = OptimizerSettings()
        self.explicit: set[str] = {f.name for f in dataclasses.fields(OptimizerSettings)
                                   if getattr(self.settings, f.name) != getattr(defaults, f.name)}  # fmt: skip
        self.latent_dim = latent_dim
        self.fast = fast
        self.constraints: list[Constraint] = []
        self._captured: dict[int, tuple[Constraint, Constraint]] = {}
        self.sensor_weights: dict[str, float] = {}
        self.configure(**overrides)
        self.reset(sk.Skeleton.canonical())

    # -- running ---------------------------------------------------------------------

    def reset(self, skeleton: sk.Skeleton, fps: float = sk.FPS, *, reference: Motion | None = None) -> None:
        self.skeleton = skeleton
        self.fps = fps
        self.optimizer = PoseOptimizer(self.decoder, skeleton.offsets, self.settings, fast=self.fast)
        self.schedule = TemporalSchedule(self.settings.predictor_every, self.settings.past_window)
        self.sensors: dict[str, SensorConstraint] = {}
        self.prior = TemporalPriorConstraint(name="temporal_prior")
        self.smooth = SmoothConstraint(name="smooth")
        self.ground = GroundConstraint(name="ground")
        self._before: torch.Tensor | None = None  # positions two frames back (smooth term)
        self._frame = 0
        self._latent = torch.zeros(self.latent_dim)
        self._root: RootFrame | None = None
        self._positions: torch.Tensor | None = None  # float32 (22, 3), the solver's view
        self._pos64: np.ndarray | None = None  # the same values in float64 (numpy users)
        self._before64: np.ndarray | None = None
        self._last: FrameResult | None = None
        self._roots: list[tuple[torch.Tensor, torch.Tensor, torch.Tensor]] = []  # see _advance
        self._effective: dict[tuple, OptimizerSettings] = {}
        self._blends: dict[str, SensorBlend] = {}
        self._facing: np.ndarray | None = None  # this frame's body heading (4,), from its trackers
        self._points: dict[str, np.ndarray] = {}  # connected trackers' positions, this frame
        self._last_points: dict[str, np.ndarray] = {}  # ... and the previous one
        self._tracks = TrackerHistory()  # recent 6-DoF readings for the tracker prior
        self._bank_prior = False  # the last frame's prior came from the pose bank
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

    def _read_frame(self, sensors: SensorFrame) -> tuple[list[str], OptimizerSettings]:
        """Take a frame's readings: sensor terms, tracker history, facing; returns the
        warnings so far and the settings the frame runs with."""
        warnings = self._update_sensors(sensors)
        self._tracks.push({j: (np.asarray(r.position, np.float64), np.asarray(r.rotation, np.float64))
                           for j, r in sensors.readings.items() if r.connected and r.dof == 6 and _finite(r)})  # fmt: skip
        points = {j: np.array(c.position, dtype=np.float64) for j, c in self.sensors.items() if c.enabled}
        self._facing = body_facing(points)
        self._last_points, self._points = self._points, points
        # the connected sensor set's profile fills the settings the caller left alone
        s = self._effective_settings()
        base = self.settings.sensor_rotation_weight
        if s.sensor_rotation_weight != base and base > 0:  # the profile's rotation weight (blend kept)
            for c in self.sensors.values():
                c.rotation_weight *= s.sensor_rotation_weight / base
        return warnings, s

    def solve_clip(self, frames: Sequence[SensorFrame]) -> list[FrameResult] | None:
        """Offline mode: the whole clip solved in windows of frames optimised together
        (:mod:`engine.methods.dragposer_batch`), or None when this clip is solved frame by
        frame (realtime mode, user constraints, no 6-DoF hip tracker in every frame...)."""
        from engine.methods.dragposer_batch import solve_clip

        return solve_clip(self, frames)

    def _step(self, sensors: SensorFrame, deadline: float | None = None) -> FrameResult:
        t0 = time.perf_counter()
        warnings, s = self._read_frame(sensors)
        self.schedule.configure(s.predictor_every, s.past_window)
        override = roots.root_override(self.sensors)
        if self._root is None:
            self._root = roots.initial_root(self.skeleton, self.sensors, self._facing)
        readings = self._tracks.arrays() if s.prior == "trackers" and self.bank is not None else None
        # the predictor runs only when its latent is the prior: while the bank answers
        # (hips or head among the 6-DoF trackers) its runs would be thrown away
        self._bank_prior = readings is not None
        if self._bank_prior:
            prediction = self.bank.latent(*readings, k=s.tracker_prior_neighbours)
            prior_weight = s.tracker_prior_weight
        else:  # a predictor run for later frames waits for between_frames (engine/solver/temporal.py)
            prediction, warn = self.schedule.prediction(self._frame, self.predictor, max(1, s.future_window),
                                                        defer=True)  # fmt: skip
            if warn:
                warnings.append(warn)
            prior_weight = s.temporal_weight
        start = prediction if prediction is not None and s.init_from_prediction else self._latent
        self.prior.weight = prior_weight
        self.smooth.weight = s.smooth_weight
        feet = any(self.sensors[j].enabled for j in ("lankle", "rankle") if j in self.sensors)
        self.ground.weight = 0.0 if feet else s.ground_weight
        # frame 0 is solved offline from the mean latent, so the step from it to frame 1 is
        # not a velocity: extrapolating it threw frames 2-4 of a head-and-hands clip 36 cm off
        self.smooth.set_history(self._pos64, self._before64 if self._frame >= 3 else None)
        anchor = roots.root_anchor(self.sensors, self.settings) if override is None else None
        if override is None and anchor is None and s.root_anchor != "none" and self._frame > 0:
            override = roots.held_root(self._root, self._points, self._last_points)
        root = roots.reference_root(self._root, self.sensors, s, override, self._facing)
        ctx = FrameContext(root, override, anchor, self._positions, prediction, self._frame, deadline)
        self.settle_constraints(self._pos64)  # e.g. an unset pin takes the previous pose
        terms = [*self.sensors.values(), self.prior, self.smooth, self.ground, *self.constraints]
        self.optimizer.settings = dataclasses.replace(s, mode="offline") if self._frame == 0 else s
        try:  # frame 0 has no history to start from: it is solved offline
            sol = self.optimizer.solve(start, terms, ctx)
        finally:
            self.optimizer.settings = self.settings
        warnings += sol.warnings
        self.last_solve = record_of(sol, ctx, terms, start is prediction, self._bank_prior)
        state = sol.state
        if not (torch.isfinite(state.positions).all() and torch.isfinite(state.local_rot).all()):
            warnings.append("decoded pose is not finite; previous pose repeated")
            return self._repeat_last(warnings, sol.losses, sol.iterations, t0)
        local_rot, positions = state.local_rot.double().numpy(), state.positions.double().numpy()
        reach_to = self._reach_targets() if s.reach else {}
        turn_to = self._rotation_targets() if s.sensor_rotations else {}
        if reach_to or turn_to:  # one FK for both steps (engine/solver/limb_ik.py)
            local_rot, positions = finish(local_rot, positions[0], self.skeleton.offsets, reach_to, turn_to,
                                          s.neck_twist_share)  # fmt: skip
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
        self._bank_later = tuple(combinations)

    def between_frames(self) -> None:
        """One piece of the temporal predictor's deferred work (engine/solver/temporal.py):
        the same latents as when the next :meth:`step` does it, without adding to that
        frame's latency (nothing while the pose bank gives the prior), and the pose bank's
        tables and combinations a method made with ``prepare_bank=False`` left for after
        its first frame (:func:`create`). Runs with the solver's torch thread count, as
        :meth:`step` does."""
        threads = torch.get_num_threads()
        if self.settings.threads:
            torch.set_num_threads(self.settings.threads)
        try:
            if self._bank_later and self.bank is not None:  # once, after the first frame
                later, self._bank_later = self._bank_later, ()
                self.bank.prepare(later)
            if not self._bank_prior:
                self.schedule.run_pending()
        finally:
            torch.set_num_threads(threads)

    def decode_latent(self, latent: np.ndarray) -> np.ndarray:
        """World joint positions ``(22, 3)`` of ``latent (L,)``, placed at the current root."""
        z = torch.as_tensor(np.asarray(latent, dtype=np.float32).reshape(self.latent_dim))
        root = self._root or roots.initial_root(self.skeleton, self.sensors, self._facing)
        with torch.no_grad():
            state = self.optimizer.decode(z, FrameContext(root))
        return state.positions.double().numpy()

    # -- internals -------------------------------------------------------------------

    def _update_sensors(self, frame: SensorFrame) -> list[str]:
        warnings: list[str] = []
        s = self.settings
        for c in self.sensors.values():
            c.enabled = False  # readings absent this frame are not used
        for joint, r in frame.readings.items():
            c = self.sensors.get(joint)
            if c is None or c.dof != r.dof:
                c = SensorConstraint(name=f"sensor:{joint}", joint=joint, dof=r.dof,
                                     weight=self.sensor_weights.get(joint, 1.0))  # fmt: skip
                self.sensors[joint] = c
            ok = _finite(r)
            if r.connected and not ok:
                warnings.append(f"sensor {joint}: non-finite reading ignored")
            c.position_tolerance, c.rotation_tolerance = s.position_tolerance, s.rotation_tolerance
            live = bool(r.connected and ok)
            # trackers that place the body (hips, root anchor) are never blended
            seconds = 0.0 if joint in ("root", s.root_anchor) else s.sensor_blend
            prev = None if self._pos64 is None else self._pos64[sk.JOINT_INDEX[joint]]
            t = self._blends.setdefault(joint, SensorBlend()).update(r.position, live, prev, seconds, self.fps)
            c.rotation_weight = s.sensor_rotation_weight * t.rotation_weight
            c.weight = self.sensor_weights.get(joint, 1.0) * t.weight
            if t.active:
                c.set_target(t.position, r.rotation if live and r.dof == 6 else None, True)
            c.connected = c.enabled = t.active
        return warnings

    def _reach_targets(self) -> dict[int, np.ndarray]:
        """Tracked wrists and ankles -> their trackers' positions (setting ``reach``): a
        limb whose shoulder/elbow (hip/knee) or end joint a user constraint holds is left
        as solved (put back on its tracker, a distance between the tracked wrists had no
        effect on the pose while its loss read as met)."""
        held = {sk.JOINT_INDEX[n] for c in self.constraints if c.enabled and c.weight > 0
                for n in c.acts_on() if n in sk.JOINT_INDEX}  # fmt: skip
        return {sk.JOINT_INDEX[j]: c.position for j, c in self.sensors.items()
                if c.enabled and c.connected and sk.JOINT_INDEX[j] in LIMBS
                and not held & {sk.JOINT_INDEX[j], *LIMBS[sk.JOINT_INDEX[j]]}}  # fmt: skip

    def _rotation_targets(self) -> dict[int, np.ndarray]:
        """The head, hands and feet -> their connected 6-DoF trackers' world rotations
        (setting ``sensor_rotations``); the hips' is the tracker's already."""
        return {sk.JOINT_INDEX[j]: c.rotation for j, c in self.sensors.items()
                if c.enabled and c.connected and c.dof == 6 and j != "root"}  # fmt: skip

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
        self.schedule.record(self._frame, latent, roots.Conditioning(tuple(self._roots), pos_t))
        self._latent = latent
        self._root = RootFrame(rot_t, pos_t[0].clone())
        self._before, self._before64 = self._positions, self._pos64
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


def _finite(r: Sensor) -> bool:
    pos = np.asarray(r.position, dtype=np.float64).tolist()
    if not all(math.isfinite(v) for v in pos):
        return False
    if r.dof == 6:
        q = np.asarray(r.rotation, dtype=np.float64).tolist()
        return all(math.isfinite(v) for v in q) and math.sqrt(sum(v * v for v in q)) > 1e-6
    return True


def create(mode: str = "realtime", iterations: int | None = None, lr: float | None = None,
           vae_path: Any = None, predictor_path: Any = None, prepare_bank: bool = True,
           **overrides: Any) -> DragPoserMethod:  # fmt: skip
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
    # the shipped pose bank holds the shipped VAE's latents: a user's VAE goes without it
    bank = default_bank() if vae_path is None else None
    if bank is not None and prepare_bank:  # the presets' lookups ready before their first frame (no cold start)
        bank.prepare(preset_combinations())
    mark("engine: pose bank ready")
    values: dict[str, Any] = {"mode": mode, **overrides}
    if iterations is not None:
        values["iterations" if mode == "realtime" else "max_iterations"] = iterations
    if lr is not None:
        values["lr"] = lr
    method = DragPoserMethod(decoder, predictor, latent_dim=decoder.config.latent, bank=bank, **values)
    if bank is not None and not prepare_bank:
        method.prepare_bank_later(preset_combinations())
    return method


def preset_combinations() -> list[tuple[str, ...]]:
    """The pose-bank combinations (:func:`engine.solver.tracker_prior.combination`) of the
    shipped sensor presets' 6-DoF trackers."""
    from engine.tracking.presets import PRESET_SENSORS

    combos = (combination(s.joint for s in sensors if s.dof == 6) for sensors in PRESET_SENSORS.values())
    return list(dict.fromkeys(c for c in combos if c is not None))
