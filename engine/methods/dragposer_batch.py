"""DragPoser's offline mode on a whole clip at once (``evaluate`` and ``reconstruct --mode
offline``).

The frame-by-frame solve carries each frame into the next (its latent is the next
start, its Adam moments go on, its pose and the one before set the next smoothing
target), so frames cannot all be solved together without changing the result: solved
jointly from the pose bank's latents, the first 150 frames of two validation files
came out at 0.90 cm / 6.29 deg against 0.83 / 5.87 frame by frame, because a frame's
start decides where the solve ends. Instead the clip is cut into segments of
:data:`SEGMENT` frames and the segments' frames are solved side by side
(:func:`engine.solver.batch.solve_streams`), each segment carrying its own state exactly
as the frame-by-frame solve does. A segment after the first starts from the pose bank's
latent and first solves the :data:`WARMUP` frames before it, so that its first kept frame
starts from a solved neighbour, not cold; those frames' solutions are dropped but for the
last :data:`FADE`, into which the previous segment's solution is cross-faded (a step at
each segment's start otherwise adds jitter). Each frame gets the same after-solve steps
(limbs onto their trackers, tracker rotations) as in a frame-by-frame solve.

*Steps.* A frame takes a fixed number of steps (:data:`STEPS`) instead of the
frame-by-frame stopping rule (tolerances, ``patience``, ``max_iterations``), which ends
most frames on ``patience``, after ten steps that no longer help, and stops the hard ones
no later than the easy ones. Frame by frame with six sensors, a fixed 40 steps per frame
is as accurate as the rule's mean of 62 (3 validation files, 300 frames: 0.793 cm / 5.872
deg against 0.801 / 5.887), and 80 or 160 steps gain nothing more. Each stream's next
frame starts from its last latent moved on by half its last change (:data:`EXTRAPOLATE`;
with the sparse sets' plain gradient steps it does worse). What the segments' starts
cost is mostly how well their warm-up frames are solved: warm-up frames, whose solutions
are dropped, take :data:`WARMUP_STEPS` steps and a segment's first frame (from the bank's
latent, fresh moments) :data:`FIRST_STEPS`. Six sensors, 300 frames: with 10 and 40, six
validation files gave 0.777 cm / 8.029 deg against 0.768 / 8.005 with 30 and 100; 20 and
100 do as well as 30 and 100 on all nine (0.775 / 7.305 against 0.775 / 7.303). Every
warm-up frame gets the after-solve steps, as its successor's smoothing target comes from
it: with only the last two finished, the nine files gave 7.305 deg instead of 7.280.

A clip is batched when the method is in offline mode on its fast path with no user
constraint, every frame has the same connected trackers, among them a 6-DoF hip
tracker (the root is then the tracker's), and the temporal prior comes from the pose
bank (the temporal predictor reads the solved history); otherwise :func:`solve_clip`
returns None and the caller steps frame by frame.
"""

from __future__ import annotations

import time
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any, Protocol

import numpy as np

from engine.constraints.base import Constraint
from engine.constraints.residual import FrameInputs, FrameRows, Term
from engine.kinematics import quat_np as QN
from engine.kinematics.fk import fk
from engine.methods.base import FrameResult
from engine.methods.dragposer_parts import FramePlan, smoothing_history
from engine.sensors import SensorFrame
from engine.solver.batch import BatchObjective, solve_streams
from engine.solver.chain import RootFrames
from engine.solver.objective import active_weights
from engine.solver.threads import one_blas_thread


class DragPoserMethod(Protocol):
    """What the batched solve takes from :class:`engine.methods.dragposer.DragPoserMethod`
    (public parts only: the frames' plans, the solver, the method's own terms)."""

    settings: Any
    skeleton: Any
    fps: float
    latent_dim: int
    priors: Any
    optimizer: Any
    prior: Any
    smooth: Any
    ground: Any

    @property
    def explicit(self) -> set[str]: ...

    @property
    def constraints(self) -> list: ...

    @property
    def sensors(self) -> dict[str, Any]: ...

    def plan(self, frame: SensorFrame) -> FramePlan: ...

    def reset(self, skeleton: Any, fps: float = ...) -> None: ...


#: Segments solved side by side (at most; fewer in a clip shorter than ``STREAMS * SEGMENT``).
STREAMS = 32
#: Frames a segment solves in order, at least. Shorter segments put more frames in each
#: decoder pass, and solve more warm-up frames twice.
SEGMENT = 16
#: Frames before its first that a segment solves first (at most :data:`SEGMENT`). They are
#: the previous segment's last frames, and the two solutions are cross-faded over them.
WARMUP = 8
#: The overlap's last frames cross-faded (:func:`_crossfade`: the previous segment's solution
#: to this segment's warm-up solution, by slerp of the local rotations) instead of cutting
#: at the segment's start. The warm-up's first frames, started cold, are not blended in.
FADE = 2
#: Steps per kept frame, by update rule (module doc, *Steps*). The frame-by-frame stopping
#: rule applies instead when the user set ``max_iterations``, ``patience`` or
#: ``min_improvement``, and always to the clip's first frame (it starts from the mean latent).
STEPS = {"adam-carry": 30, "adam": 30, "sgd": 15}
#: Steps per warm-up frame: its solution is dropped, it only brings the stream's latent,
#: moments and smoothing history to the segment's first kept frame.
WARMUP_STEPS = 20
#: Steps of a later segment's first warm-up frame, which starts from the pose bank's latent
#: with fresh moments.
FIRST_STEPS = 100
#: A stream's next frame starts from its last latent plus this share of the latent's last
#: change (by update rule; the plain gradient steps of the sparse sets do worse with it).
EXTRAPOLATE = {"adam-carry": 0.5, "adam": 0.5, "sgd": 0.0}
#: Settings that ask for the frame-by-frame stopping rule.
RULE_SETTINGS = frozenset({"max_iterations", "patience", "min_improvement"})


@dataclass(frozen=True)
class BatchFrame:
    """One frame of the batched solve, read before any frame is solved.

    Attributes
    ----------
    plan : FramePlan
        What the frame is solved against (:meth:`DragPoserMethod.plan`), with a 6-DoF hip
        tracker (``plan.hip``) and the pose bank's lookup input (``plan.bank_readings``).
    own : tuple of Constraint
        The method's own constraints (temporal prior, smoothing, ground band) this frame
        keeps, by the frame-by-frame solve's rule (:func:`active_weights`), in that order.
    weights : ndarray (K,)
        The weights of the frame's terms: the trackers' (``plan.weights``), then ``own``'s.
    prior : ndarray (L,)
        The pose bank's latent for the frame: the temporal prior's target, and the start
        of a segment that begins here.
    """

    plan: FramePlan
    own: tuple[Constraint, ...]
    weights: np.ndarray
    prior: np.ndarray

    def terms(self, smooth_history: tuple[np.ndarray | None, np.ndarray | None], m: DragPoserMethod) -> list[Term]:
        """The frame's terms (trackers, then ``own``'s), the smoothing target from the
        stream's last two solved poses ``smooth_history`` (:func:`smoothing_history`)."""
        m.smooth.set_history(*smooth_history)
        inputs = FrameInputs(prediction=self.prior)
        assert self.plan.trackers is not None  # a batched frame's plan holds its term (_plan)
        return [self.plan.trackers, *(c.term(inputs) for c in self.own)]


def solve_clip(m: DragPoserMethod, frames: Sequence[SensorFrame]) -> list[FrameResult] | None:
    """The clip's frames solved by ``m`` (a :class:`~engine.methods.dragposer.DragPoserMethod`
    just reset), or None (method left reset) when the clip is not batched (module doc)."""
    with one_blas_thread():  # as the per-frame solver: more threads only wait
        return _solve_clip(m, frames)


def _solve_clip(m: DragPoserMethod, frames: Sequence[SensorFrame]) -> list[FrameResult] | None:
    fast = m.optimizer.fast_parts
    if m.settings.mode != "offline" or fast is None or not frames or not _same_hip_set(frames):
        return None
    if any(c.enabled and c.weight > 0 for c in m.constraints):
        return None
    t0 = time.perf_counter()
    read = _read_all(m, frames)
    if read is None:
        m.reset(m.skeleton, m.fps)
        return None
    s = read[0].plan.settings
    rule = m.optimizer.update_rule([c for c in m.sensors.values() if c.enabled], settings=s)
    if rule not in ("sgd", "adam", "adam-carry") or (rule == "sgd" and s.momentum > 0):
        m.reset(m.skeleton, m.fps)
        return None
    fixed = None if m.explicit & RULE_SETTINGS else STEPS.get(rule)
    ahead = np.float32(EXTRAPOLATE.get(rule, 0.0) if fixed is not None else 0.0)
    n = len(frames)
    seg = max(SEGMENT, -(-n // STREAMS))
    keep_from = list(range(0, n, seg))  # each segment's first kept frame
    first = [max(0, a - min(WARMUP, seg)) for a in keep_from]  # warm-up within the previous segment
    end = [min(n, a + seg) for a in keep_from]
    c_all = len(keep_from)
    at = [f - 1 for f in first]  # each segment's current frame
    hist: list[list[np.ndarray]] = [[] for _ in range(c_all)]  # its last two finished poses
    z = _starts(read, first, m.latent_dim)
    objective = _objective(m, read[0], c_all)
    results: list[FrameResult | None] = [None] * n
    overlap: dict[int, np.ndarray] = {}  # frame -> the next segment's warm-up local rotations

    def load(c: int) -> bool:
        at[c] += 1
        if at[c] >= end[c]:
            return False
        f = at[c]
        solved = z[c].copy()
        if f > first[c] + 1 and ahead:  # the stream's last two latents give a velocity
            z[c] += ahead * (solved - last_z[c])
        last_z[c] = solved
        h = hist[c]
        r = read[f]
        assert r.plan.hip is not None  # a batched frame has a 6-DoF hip tracker
        history = smoothing_history(f, h[-1] if h else None, h[-2] if len(h) == 2 else None)
        objective.set_row(c, r.terms(history, m), r.weights, *r.plan.hip)
        return True

    def done(c: int, iterations: int) -> None:
        f = at[c]
        local, pos = _finished(m, read[f], *objective.row(c)[::-1])
        hist[c] = [*hist[c][-1:], pos]
        if f < keep_from[c]:
            overlap[f] = local
        if f >= keep_from[c]:
            values = objective.values[c]
            losses = {**dict(zip(objective.names, values.tolist())), "total": float(objective.weights[c] @ values)}
            results[f] = FrameResult(
                local_rot=local,
                root_pos=pos[0].copy(),
                positions=pos,
                iterations=iterations,
                losses=[losses],
                latent=z[c].astype(np.float64),
                ms=0.0,
                warnings=read[f].plan.warnings,
                timings={},
            )

    lr = s.step_size if rule == "sgd" else s.lr
    last_z = z.copy()

    def steps(c: int) -> int | None:
        f = at[c]
        if fixed is None or f == 0:
            return None
        return FIRST_STEPS if f == first[c] else WARMUP_STEPS if f < keep_from[c] else fixed

    solve_streams(objective, z, rule, lr, s.max_iterations, s.patience, s.min_improvement, load, done, steps)
    ms = 1000.0 * (time.perf_counter() - t0) / n
    for a, b in zip(first[1:], keep_from[1:]):
        a = max(a, b - FADE)
        _crossfade(results[a:b], [overlap[f] for f in range(a, b) if f in overlap], m.skeleton.offsets)
    out = [r for r in results if r is not None]
    m.reset(m.skeleton, m.fps)  # the segments leave no single history to continue from
    if not all(np.isfinite(r.positions).all() for r in out):
        return None  # no divergence fall-back here: the frame-by-frame solve has one
    for res in out:
        res.ms = ms  # the clip's solve time shared by its frames
    return out


def _starts(read: list[BatchFrame], first: list[int], latent_dim: int) -> np.ndarray:
    """Each segment's starting latent ``(C, L)`` float32: the clip's first frame starts from
    the mean latent (zeros, as frame by frame), a later segment from the pose bank's latent
    of its first warm-up frame (``first[c]``)."""
    z = np.zeros((len(first), latent_dim), np.float32)
    for c in range(1, len(first)):
        z[c] = read[first[c]].prior
    return z


def _crossfade(own: Sequence[FrameResult | None], warm: list[np.ndarray], offsets: np.ndarray) -> None:
    """Blend the ``W`` frames ``own`` (the previous segment's last, in order) towards
    ``warm`` (the next segment's warm-up solutions of the same frames, local rotations
    ``(22, 4)``) with weights ``1/(W+1) .. W/(W+1)``, so the next segment's first kept
    frame follows on without a step; positions are recomputed by forward kinematics
    (the root position is the hip tracker's in both)."""
    done = [r for r in own if r is not None]
    if not warm or len(warm) != len(own) or len(done) != len(own):
        return
    alpha = np.arange(1, len(done) + 1) / (len(done) + 1.0)
    q0 = np.array([r.local_rot for r in done])
    q1 = np.array(warm)
    q1 = q1 * np.where((q0 * q1).sum(-1, keepdims=True) < 0, -1.0, 1.0)  # one hemisphere per joint
    blend = QN.slerp(q0, q1, alpha[:, None, None])
    pos, _ = fk(blend, np.array([r.root_pos for r in done]), offsets)
    for r, q, p in zip(done, blend, pos):
        r.local_rot, r.positions, r.root_pos = q, p, p[0].copy()


def _finished(m: DragPoserMethod, r: BatchFrame, local: np.ndarray, pos: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """A solved frame after the limb and tracker-rotation steps of a frame-by-frame solve."""
    return r.plan.finished(local, pos, m.skeleton.offsets)


def _same_hip_set(frames: Sequence[SensorFrame]) -> bool:
    """Every frame has the same connected trackers, a 6-DoF hip tracker among them."""
    first = None
    for f in frames:
        live = frozenset((j, r.dof) for j, r in f.readings.items() if r.connected)
        if ("root", 6) not in live or (first is not None and live != first):
            return False
        first = live
    return True


def _read_all(m: DragPoserMethod, frames: Sequence[SensorFrame]) -> list[BatchFrame] | None:
    """Every frame's :class:`BatchFrame`, or None when a frame cannot be batched
    (:func:`_plan`) or the frames do not share their trackers and terms."""
    found = [_plan(m, f) for f in frames]
    plans = [p for p in found if p is not None]
    if len(plans) != len(found):
        return None
    own = [_own(m, p, f.frame) for p, f in zip(plans, frames)]
    banks = [p.bank_readings for p in plans if p.bank_readings is not None]  # all of them (_plan)
    if len({(p.names, b[0], tuple(c.name for c, _ in o)) for p, b, o in zip(plans, banks, own)}) != 1:
        return None
    joints = banks[0][0]  # all frames' priors in one call, as frame by frame finds them
    pos, rot = np.array([b[1] for b in banks]), np.array([b[2] for b in banks])
    priors = m.priors.latent_frames(plans[0].settings, joints, pos, rot)
    return [
        BatchFrame(
            plan=p,
            own=tuple(c for c, _ in o),
            weights=np.concatenate([np.asarray(p.weights, dtype=np.float64), [w for _, w in o]]),
            prior=z,
        )
        for p, o, z in zip(plans, own, priors)
    ]


def _plan(m: DragPoserMethod, frame: SensorFrame) -> FramePlan | None:
    """The frame's :class:`FramePlan` (as ``m.step`` would make it), or None when the frame
    cannot be batched (its prior is not the pose bank's, no 6-DoF hip tracker, or a
    reading is not finite)."""
    plan = m.plan(frame)
    if plan.bank_readings is None or plan.hip is None or plan.warnings:
        return None
    return plan


def _own(m: DragPoserMethod, plan: FramePlan, frame: int) -> list[tuple[Constraint, float]]:
    """The method's own constraints a frame keeps and their weights, weighted as the
    frame-by-frame step weights them with the pose bank's prior."""
    m.prior.weight = plan.settings.tracker_prior_weight
    m.smooth.weight, m.ground.weight = plan.smooth_weight, plan.ground_weight
    return list(zip(*active_weights([m.prior, m.smooth, m.ground], frame)))


def _objective(m: DragPoserMethod, r: BatchFrame, rows: int) -> BatchObjective:
    """The batched objective with ``rows`` rows, each the frame ``r`` (without smoothing
    target) until :meth:`~engine.solver.batch.BatchObjective.set_row` gives it its own."""
    assert r.plan.hip is not None
    terms = [t.rows(rows) if isinstance(t, FrameRows) else t for t in r.terms((None, None), m)]
    position, rotation = r.plan.hip
    q = np.tile(rotation, (rows, 1))
    root = RootFrames(
        heading=np.tile(np.eye(3), (rows, 1, 1)),
        previous=np.zeros((rows, 3)),
        position=np.tile(position, (rows, 1)),
        rotation=QN.to_matrix(q),
    )
    return BatchObjective(
        m.optimizer.fast_parts.decoder,
        m.skeleton.offsets,
        terms,
        np.tile(r.weights, (rows, 1)),
        root,
        QN.canonicalize(q),
    )
