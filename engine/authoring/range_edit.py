"""Range edits: re-solve a frame range of a loaded clip with added constraints, offline.

The range ``[start, end]`` with ``blend`` frames on each side is solved frame by frame
through the pose VAE on the clip's own skeleton and root trajectory: each frame starts
from the encoder's latent of the original frame, is pulled towards it (so what no
constraint asks for stays as it was) and meets the added constraints (weights times
their own frame ranges' activity) with the smoothing term on the frames solved before it.

The clip's detail is kept: what replaces a frame is the original rotations times the
change the solve made to the decoded pose (``q_orig * q_dec0^-1 * q_dec``, per joint),
not the decoded pose itself, so a constraint that asks for nothing changes nothing
beyond the autoencoder's noise on the change. Then two exact steps: feet in floor
contact (a ``floor`` constraint in the edit) are held where the contact began, and
wrist / ankle pins and end-effector targets are put on their targets, by the limbs'
two bones. The result is blended with the original over the blend frames (slerp by a
smoothstep weight); every frame outside the range and its blends is the original's, bit
for bit.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from engine import skeleton as sk
from engine.authoring.bake import active_constraints
from engine.authoring.character import Character
from engine.authoring.pose_mode import encode_frames
from engine.constraints.base import Constraint
from engine.constraints.end_effector import EndEffectorConstraint
from engine.constraints.floor import FloorConstraint
from engine.constraints.pin import PinConstraint
from engine.constraints.smooth import SmoothConstraint
from engine.errors import UserError
from engine.kinematics import quat_np as QN
from engine.kinematics import quaternion as Q
from engine.kinematics.fk import fk
from engine.motion.clip import Motion
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
#: Foot end joints held in contact (the ankles; their limbs reach).
FOOT_ENDS = {"ltoe": "lankle", "rtoe": "rankle", "lankle": "lankle", "rankle": "rankle"}


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


def edit_range(vae, motion: Motion, start: int, end: int, constraints: list[Constraint],
               blend: int = 8) -> RangeEdit:  # fmt: skip
    """Re-solve frames ``start..end`` (inclusive) of ``motion`` with ``constraints`` and
    blend ``blend`` frames at each end (see the module doc)."""
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
    for i, f in enumerate(frames):
        previous_rot = motion.local_rot[max(f - 1, 0), 0]
        ctx = character.placed(motion.root_pos[f], frame=f, previous=history[-1] if history else None,
                               prior=latents[i], reference=previous_rot, ground=False)  # fmt: skip
        base = character.decode(latents[i], ctx)
        smooth.set_history(history[-1] if history else None, history[-2] if len(history) > 1 else None)
        terms = [*active_constraints(constraints, f), smooth]
        solved = character.solve(latents[i], terms, ctx, iterations=ITERATIONS, prior_weight=PRIOR_WEIGHT, rule="sgd",
                                 step_size=STEP_SIZE)  # fmt: skip
        delta = QN.mul(QN.conjugate(base.local_rot), solved.local_rot)
        edited = QN.mul(motion.local_rot[f], delta)
        out_local[f] = Q.slerp(motion.local_rot[f], edited, np.full((sk.NUM_JOINTS, 1), weight[i]))
        history.append(fk(out_local[f], motion.root_pos[f], offsets)[0])
    _exact_steps(out_local, motion, constraints, frames, weight)
    out_local[:lo] = motion.local_rot[:lo]
    out_local[hi + 1 :] = motion.local_rot[hi + 1 :]
    result = Motion(out_local, motion.root_pos.copy(), motion.skeleton, motion.fps, motion.name)
    return RangeEdit(result, lo, hi)


def _weights(start: int, end: int, blend: int, lo: int, hi: int) -> np.ndarray:
    """Blend weight of every frame ``lo..hi``: 1 on the range, a smoothstep outside."""
    out = []
    for f in range(lo, hi + 1):
        gap = start - f if f < start else f - end if f > end else 0
        t = 1.0 - gap / (blend + 1)
        out.append(t * t * (3 - 2 * t))
    return np.array(out)


def _exact_steps(local: np.ndarray, motion: Motion, constraints: list[Constraint], frames: list[int],
                 weight: np.ndarray) -> None:  # fmt: skip
    """Feet held in floor contact, then wrist / ankle targets, in place on ``local``."""
    offsets = motion.skeleton.offsets
    floors = [c for c in constraints if isinstance(c, FloorConstraint) and c.enabled]
    held: dict[int, np.ndarray] = {}
    for i, f in enumerate(frames):
        pos = fk(local[f], motion.root_pos[f], offsets)[0]
        was = fk(motion.local_rot[f], motion.root_pos[f], offsets)[0]  # contact is read off the clip
        targets: dict[int, np.ndarray] = {}
        for c in floors:
            if c.activity(f) <= 0:
                continue
            for name in c.joints:
                ankle = sk.JOINT_INDEX[FOOT_ENDS.get(name, "")] if name in FOOT_ENDS else None
                if ankle is None:
                    continue
                j = sk.JOINT_INDEX[name]
                if was[j, 2] < c.floor_height + c.contact_height:
                    if ankle not in held:
                        held[ankle] = pos[ankle].copy()
                    targets[ankle] = np.array([*held[ankle][:2], pos[ankle, 2]])
        for ankle in [a for a in held if a not in targets]:
            del held[ankle]  # the foot lifted: a new contact starts where it lands
        for c in constraints:
            if not isinstance(c, (PinConstraint, EndEffectorConstraint)):
                continue  # only these hold one joint at a position
            a = c.activity(f) if c.enabled else 0.0
            j = sk.JOINT_INDEX.get(c.joint, -1)
            p = c.position
            if a > 0 and j in LIMBS and p is not None and np.shape(p) == (3,) and np.isfinite(p).all():
                targets[j] = pos[j] + a * (np.asarray(p, float) - pos[j])
        if targets:
            moved = {j: pos[j] + weight[i] * (t - pos[j]) for j, t in targets.items()}
            local[f] = reach_local(local[f], motion.root_pos[f], offsets, moved)
