"""Range edits: re-solve a frame range of a loaded clip with added constraints, offline.

The range ``[start, end]`` with ``blend`` frames on each side is solved frame by frame
through the pose VAE on the clip's own skeleton and root trajectory: each frame starts
from the encoder's latent of the original frame, is pulled towards it (so what no
constraint asks for stays as it was) and meets the added constraints (weights times
their own frame ranges' activity) with the smoothing term on the frames solved before it.

The clip's detail is kept: what replaces a frame is the original rotations times the
change the solve made to the decoded pose (``q_orig * q_dec0^-1 * q_dec``, per joint),
not the decoded pose itself, so a constraint that asks for nothing changes nothing
beyond the autoencoder's noise on the change. Each frame's solve starts afresh from its
own latent, so that change is smoothed over time (:data:`SMOOTH_FRAMES`) before it is
applied: frame-to-frame differences of the solve made a limb pop. The result is
blended with the original over the blend frames (slerp by a smoothstep weight), then
two exact steps: feet in floor contact in the clip (a ``floor`` constraint in the
edit) are held where the contact began (the ankle when it is down, else the toe, the
ankle following it), and when the clip lifts the foot the hold eases off over
:data:`RELEASE_FRAMES`; wrist / ankle pins and end-effector targets are put on their
targets, by the limbs' two bones. Last, a guard: where a joint still moves more in a
frame than :func:`step_limit` allows, the edit's weight is lowered around that frame
until none does. Every frame outside the range and its blends is the original's, bit
for bit.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from engine import skeleton as sk
from engine.authoring.character import Character, encode_frames
from engine.authoring.pins import active_constraints
from engine.constraints.base import Constraint
from engine.constraints.end_effector import EndEffectorConstraint
from engine.constraints.floor import FloorConstraint
from engine.constraints.pin import PinConstraint
from engine.constraints.smooth import SmoothConstraint
from engine.errors import UserError
from engine.kinematics import quat_np as QN
from engine.kinematics import quaternion as Q
from engine.kinematics.fk import fk, fk_positions
from engine.motion.clip import Motion
from engine.progress import CancelCheck, check
from engine.solver.limb_ik import LIMBS, reach_local

#: Latent steps per frame and their plain gradient step. With the shipped VAE, steps of
#: 0.1-0.2 (10 steps) hold a planted foot within 1 cm/frame and put a raised hand on its
#: target on every frame of the range; from 0.45 (or 20 x 0.15) the latent moves so far
#: from the clip's own pose that the foot slides again and the hand leaves its reach.
ITERATIONS = 10
STEP_SIZE = 0.15
#: Pull towards the original frame's latent.
PRIOR_WEIGHT = 0.1
SMOOTH_WEIGHT = 1.0
#: Half-width of the window (frames) that smooths the solve's change over time: at 60 fps
#: on CMU clips, 0 left steps of 10-25 cm in the range where the clip moved 5-17 cm.
SMOOTH_FRAMES = 4
#: Frames over which a released foot hold eases off.
RELEASE_FRAMES = 6
#: The guard's floor of the step limit, metres: a still clip may move a few cm anyway.
MIN_STEP_LIMIT = 0.03


@dataclass
class RangeEdit:
    """What a range edit changed.

    Attributes
    ----------
    motion : Motion
        The whole clip with the range replaced.
    first, last : int
        The frames that may differ from the original (the range and its blends).
    """

    motion: Motion
    first: int
    last: int


def edit_range(
    vae,
    motion: Motion,
    start: int,
    end: int,
    constraints: list[Constraint],
    blend: int = 8,
    progress: Callable[[int, int], None] | None = None,
    cancelled: CancelCheck | None = None,
) -> RangeEdit:
    """Re-solve frames ``start..end`` (inclusive) of ``motion`` with ``constraints`` and
    blend ``blend`` frames at each end (see the module doc).

    ``progress(done, total)`` is called after each solved frame (``total``: the range
    with its blends); ``cancelled()`` is asked before each and a True answer raises
    :class:`engine.progress.Cancelled`. ``motion`` and ``constraints`` are
    only read: the result is a new clip."""
    n = len(motion)
    if not (0 <= start <= end < n):
        raise UserError(f"range {start}-{end} is not within the clip's frames 0-{n - 1}")
    if blend < 0:
        raise UserError(f"blend must be >= 0 frames, got {blend}")
    lo, hi = max(0, start - blend), min(n - 1, end + blend)
    weight = _weights(start, end, blend, lo, hi)
    character = Character(vae, skeleton=motion.skeleton)
    frames = list(range(lo, hi + 1))
    latents = encode_frames(vae, motion, frames)
    smooth = SmoothConstraint(name="range smooth", weight=SMOOTH_WEIGHT)
    out_local = motion.local_rot.copy()
    offsets = motion.skeleton.offsets
    history: list[np.ndarray] = []
    deltas = np.zeros((len(frames), sk.NUM_JOINTS, 4))
    for i, f in enumerate(frames):
        check(cancelled)
        previous_rot = motion.local_rot[max(f - 1, 0), 0]
        ctx = character.placed(
            motion.root_pos[f],
            frame=f,
            previous=history[-1] if history else None,
            prior=latents[i],
            reference=previous_rot,
            ground=False,
        )
        base = character.decode(latents[i], ctx)
        smooth.set_history(history[-1] if history else None, history[-2] if len(history) > 1 else None)
        terms = [*active_constraints(constraints, f), smooth]
        solved = character.solve(
            latents[i], terms, ctx, iterations=ITERATIONS, prior_weight=PRIOR_WEIGHT, rule="sgd", step_size=STEP_SIZE
        )
        deltas[i] = QN.mul(QN.conjugate(base.local_rot), solved.local_rot)
        edited = QN.mul(motion.local_rot[f], deltas[i])
        out_local[f] = Q.slerp(motion.local_rot[f], edited, np.full((sk.NUM_JOINTS, 1), weight[i]))
        history.append(fk(out_local[f], motion.root_pos[f], offsets)[0])
        if progress is not None:
            progress(i + 1, len(frames))
    full = QN.mul(motion.local_rot[lo : hi + 1], smooth_rotations(deltas, SMOOTH_FRAMES))
    limit = step_limit(motion, lo, hi)
    for _ in range(40):
        check(cancelled)
        out_local = motion.local_rot.copy()
        out_local[lo : hi + 1] = Q.slerp(motion.local_rot[lo : hi + 1], full, weight[:, None, None])
        _exact_steps(out_local, motion, constraints, frames, weight, end)
        bad = _pops(out_local, motion, lo, hi, limit)
        if not bad:
            break
        for t in bad:  # the transition t -> t + 1 jumps: ease the edit off around it
            near = np.arange(lo, hi + 1)
            reach = np.minimum(np.abs(near - t), np.abs(near - t - 1))
            weight = weight * np.where(reach <= SMOOTH_FRAMES, 0.5 + 0.5 * reach / (SMOOTH_FRAMES + 1), 1.0)
    result = Motion(out_local, motion.root_pos.copy(), motion.skeleton, motion.fps, motion.name, motion.start)
    return RangeEdit(result, lo, hi)


def step_limit(motion: Motion, lo: int, hi: int) -> float:
    """The most any joint may move in one frame of an edit of frames ``lo..hi``: the
    larger of 1.5 x the clip's own largest joint step there (one frame either side
    included) and :data:`MIN_STEP_LIMIT`, metres."""
    a, b = max(lo - 1, 0), min(hi + 1, len(motion) - 1)
    pos = fk_positions(motion.local_rot[a : b + 1], motion.root_pos[a : b + 1], motion.skeleton.offsets)
    steps = np.linalg.norm(np.diff(pos, axis=0), axis=-1)
    return max(1.5 * float(steps.max(initial=0.0)), MIN_STEP_LIMIT)


def _pops(local: np.ndarray, motion: Motion, lo: int, hi: int, limit: float) -> list[int]:
    """Frames ``t`` whose step to ``t + 1`` moves some joint more than ``limit`` metres."""
    a, b = max(lo - 1, 0), min(hi + 1, len(motion) - 1)
    pos = fk_positions(local[a : b + 1], motion.root_pos[a : b + 1], motion.skeleton.offsets)
    steps = np.linalg.norm(np.diff(pos, axis=0), axis=-1).max(axis=-1)
    return [a + int(t) for t in np.flatnonzero(steps > limit)]


def smooth_rotations(q: np.ndarray, half: int) -> np.ndarray:
    """Each rotation of ``q (F, J, 4)`` averaged with its ``half`` neighbours on each side
    (a triangle window, each neighbour on the frame's own hemisphere, renormalized)."""
    if half <= 0 or len(q) < 2:
        return q.copy()
    out = np.zeros_like(q)
    for f in range(len(q)):
        acc = np.zeros(q.shape[1:])
        for g in range(max(0, f - half), min(len(q), f + half + 1)):
            w = 1.0 - abs(g - f) / (half + 1)
            sign = np.sign(np.sum(q[g] * q[f], axis=-1, keepdims=True))
            acc += w * np.where(sign == 0, 1.0, sign) * q[g]
        out[f] = acc / np.linalg.norm(acc, axis=-1, keepdims=True)
    return out


def _weights(start: int, end: int, blend: int, lo: int, hi: int) -> np.ndarray:
    """Blend weight of every frame ``lo..hi``: 1 on the range, a smoothstep outside."""
    out = []
    for f in range(lo, hi + 1):
        gap = start - f if f < start else f - end if f > end else 0
        t = 1.0 - gap / (blend + 1)
        out.append(t * t * (3 - 2 * t))
    return np.array(out)


def _exact_steps(
    local: np.ndarray, motion: Motion, constraints: list[Constraint], frames: list[int], weight: np.ndarray, end: int
) -> None:
    """Feet held in floor contact, then wrist / ankle targets, in place on ``local`` (see
    the module doc); ``end``: the range's last frame (after it a hold fades with ``weight``)."""
    offsets = motion.skeleton.offsets
    floors = [c for c in constraints if isinstance(c, FloorConstraint) and c.enabled]
    feet = [Foot(sk.JOINT_INDEX[t], sk.JOINT_INDEX[a]) for a, t in sk.FEET.values()]
    for i, f in enumerate(frames):
        pos = fk_positions(local[f], motion.root_pos[f], offsets)
        was = fk_positions(motion.local_rot[f], motion.root_pos[f], offsets)  # contact is read off the clip

        def down(j: int, f: int = f, was: np.ndarray = was) -> bool:  # this frame's f and was, bound
            return any(
                c.activity(f) > 0 and sk.JOINT_NAMES[j] in c.joints and was[j, 2] < c.floor_height + c.contact_height
                for c in floors
            )

        keep = 1.0 if f <= end else weight[i]  # the blend out returns to the clip
        targets: dict[int, np.ndarray] = {}
        aims: dict[int, tuple[int, np.ndarray]] = {}
        for foot in feet:
            shift, toe = foot.step(pos, was, down(foot.ankle), down(foot.toe), keep)
            if np.any(shift):
                targets[foot.ankle] = pos[foot.ankle] + np.array([*shift, 0.0])
            if toe is not None:
                aims[foot.ankle] = (foot.toe, toe)
        for c in constraints:
            if not isinstance(c, (PinConstraint, EndEffectorConstraint)):
                continue  # only these hold one joint at a position
            a = c.activity(f) if c.enabled else 0.0
            j = sk.JOINT_INDEX.get(c.joint, -1)
            p = c.position
            if a > 0 and j in LIMBS and p is not None and np.shape(p) == (3,) and np.isfinite(p).all():
                at = targets.get(j, pos[j])
                targets[j] = at + weight[i] * a * (np.asarray(p, float) - at)
                aims.pop(j, None)
        if targets:
            local[f] = reach_local(local[f], motion.root_pos[f], offsets, targets)
        if aims:
            _aim_feet(local[f], motion.root_pos[f], offsets, aims)


def _aim_feet(
    local: np.ndarray, root: np.ndarray, offsets: np.ndarray, aims: dict[int, tuple[int, np.ndarray]]
) -> None:
    """Turn each ankle of ``aims`` (ankle -> (toe, horizontal toe target)) so that its toe
    is over the target at its own height, in place on ``local (22, 4)``."""
    pos, rot = fk(local, root, offsets)
    for ankle, (toe, xy) in aims.items():
        bone = pos[toe] - pos[ankle]
        goal = np.array([xy[0], xy[1], pos[toe, 2]]) - pos[ankle]
        turn = QN.from_to(bone, goal * (np.linalg.norm(bone) / max(float(np.linalg.norm(goal)), 1e-9)))
        parent = rot[sk.PARENTS[ankle]]
        local[ankle] = QN.normalize(QN.mul(QN.conjugate(parent), QN.mul(turn, rot[ankle])))


class Foot:
    """The hold of one foot over the frames of a range edit: where its ankle and toe are
    kept while the clip has them down, and the shift that eases off after it lifts them."""

    def __init__(self, toe: int, ankle: int) -> None:
        self.toe, self.ankle = toe, ankle
        self.ankle_at: np.ndarray | None = None  # where the ankle is held (horizontal), metres
        self.toe_at: np.ndarray | None = None
        self.applied = np.zeros(2)  # the ankle's last shift, metres
        self.released = np.zeros(2)  # the shift when the hold ended
        self.fading = 0  # frames since the hold ended

    def step(
        self, pos: np.ndarray, was: np.ndarray, ankle_down: bool, toe_down: bool, keep: float
    ) -> tuple[np.ndarray, np.ndarray | None]:
        """The ankle's horizontal shift (2,) on a frame whose free pose is ``pos (22, 3)``
        and the clip's ``was (22, 3)``, and where its toe is held when both are down
        (None otherwise); ``keep`` < 1 (the blend out) moves the holds that much of the
        way back to the clip."""
        a, t = pos[self.ankle, :2], pos[self.toe, :2]
        # a new contact is held where the clip has it: the edit's blend out then returns
        # to a foot that has barely moved, where a hold of the edited foot slid back
        self.ankle_at = (self.ankle_at if self.ankle_at is not None else was[self.ankle, :2]) if ankle_down else None
        self.toe_at = (self.toe_at if self.toe_at is not None else was[self.toe, :2]) if toe_down else None
        ankle_at = None if self.ankle_at is None else self.ankle_at + (1 - keep) * (was[self.ankle, :2] - self.ankle_at)
        toe_at = None if self.toe_at is None else self.toe_at + (1 - keep) * (was[self.toe, :2] - self.toe_at)
        if ankle_at is not None:
            shift = ankle_at - a
        elif toe_at is not None:
            shift = toe_at - t  # heel up: the ankle follows the planted toe
        else:
            if self.fading == 0:
                self.released = self.applied
            self.fading += 1
            s = min(self.fading / (RELEASE_FRAMES + 1), 1.0)
            shift = self.released * (1.0 - s * s * (3 - 2 * s))
        if ankle_down or toe_down:
            self.fading = 0
        self.applied = shift
        return shift, (toe_at if ankle_down and toe_down else None)
