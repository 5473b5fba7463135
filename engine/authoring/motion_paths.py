"""Motion paths: where joints go over a range of frames, as Blender and Cascadeur draw them.

A :class:`MotionPaths` holds every joint's world position on each frame of a range and
the frames to mark on the path (the keys). The views draw the lines of a few joints
from it (the selected one, the feet) and a dot on the current frame; picking which
joints to draw needs no new computation.

Three sources:

* :func:`clip_paths`: a clip's frames (the studio: the opened clip, the re-solved one
  after a range re-solve), marked every second;
* :func:`baked_paths`: an authored animation's bake over its keyed range, marked on the keys;
* :func:`keyed_paths`: the same range before the bake, from the keys' latents and the
  in-between rules of the bake (:mod:`engine.authoring.keys`): the latents, root
  placements and facings interpolated and decoded in one batch, plus the interpolated
  gap each key leaves between its decoded latent and its exact pose (its targets taken
  by the limbs), so the path passes through every key and changes with no solve
  (tens of milliseconds for a few seconds of animation, where the bake takes seconds).
  The bake then refines the in-betweens; keys without a latent (a scene written by
  hand) are posed only by the bake, so this preview leaves them out. A pin against a
  target wins as in the bake (:func:`engine.authoring.pins.pinned_targets`): on the
  keys and on the in-betweens the limbs reach the targets the pins leave.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from engine import skeleton as sk
from engine.authoring.keys import Key, interpolate
from engine.authoring.pins import pinned_targets
from engine.kinematics.fk import fk_positions
from engine.motion.clip import Motion

if TYPE_CHECKING:  # the studio's window draws clip paths without torch, which these bring
    from engine.authoring.bake import Baked
    from engine.authoring.character import Character
    from engine.constraints.base import Constraint

#: The joints drawn as the feet's paths.
FEET = ("lankle", "rankle")


@dataclass(frozen=True, eq=False)
class MotionPaths:
    """Joint positions over frames ``first .. first + len(positions) - 1``.

    Attributes
    ----------
    first : int
        Frame of row 0.
    positions : ndarray (F, 22, 3)
        World joint positions per frame, metres (read-only).
    marks : tuple of int
        Frames to mark with a dot (keys; for a clip, every second).
    exact : bool
        Whether the positions are the motion itself (a clip, a bake) or a preview of it
        (:func:`keyed_paths`).
    """

    first: int
    positions: np.ndarray
    marks: tuple[int, ...] = ()
    exact: bool = True

    def __post_init__(self) -> None:
        p = np.array(self.positions, dtype=np.float64)
        if p.ndim != 3 or p.shape[1:] != (len(sk.JOINT_NAMES), 3):
            raise ValueError(f"motion path positions: expected (F, {len(sk.JOINT_NAMES)}, 3), got {p.shape}")
        p.flags.writeable = False
        object.__setattr__(self, "positions", p)
        object.__setattr__(self, "marks", tuple(int(f) for f in self.marks if self.covers(int(f))))

    @property
    def last(self) -> int:
        """The last frame of the range."""
        return self.first + len(self.positions) - 1

    def covers(self, frame: int) -> bool:
        return self.first <= frame <= self.last

    def line(self, joint: str) -> np.ndarray:
        """The path of ``joint``, ``(F, 3)`` metres."""
        return self.positions[:, sk.JOINT_INDEX[joint]]

    def at(self, joint: str, frame: int) -> np.ndarray | None:
        """Where ``joint`` is on ``frame`` (3,) metres; None outside the range."""
        return self.positions[frame - self.first, sk.JOINT_INDEX[joint]] if self.covers(frame) else None


def path_joints(selected: str | None, feet: bool) -> tuple[str, ...]:
    """The joints whose paths are drawn: the ``selected`` one (None: none) and, with
    ``feet``, both ankles, each once."""
    joints = [] if selected is None or selected not in sk.JOINT_INDEX else [selected]
    return tuple(dict.fromkeys(joints + (list(FEET) if feet else [])))


def clip_paths(motion: Motion, start: int = 0, end: int | None = None) -> MotionPaths:
    """The paths of ``motion`` over frames ``start .. end`` (None: to its end), marked
    on every whole second of the clip."""
    n = len(motion)
    end = n - 1 if end is None else min(int(end), n - 1)
    start = max(0, min(int(start), end))
    positions = fk_positions(
        motion.local_rot[start : end + 1], motion.root_pos[start : end + 1], motion.skeleton.offsets
    )
    step = max(1, int(round(motion.fps)))
    return MotionPaths(start, positions, tuple(range(0, end + 1, step)))


def keyed_range(keys: list[Key]) -> tuple[int, int] | None:
    """First and last keyed frame; None without keys."""
    if not keys:
        return None
    frames = [k.frame for k in keys]
    return min(frames), max(frames)


def baked_paths(baked: Baked, keys: list[Key]) -> MotionPaths | None:
    """The bake's paths over the keyed range (None without keys)."""
    span = keyed_range(keys)
    if span is None:
        return None
    clip = clip_paths(baked.motion, span[0], span[1])
    return MotionPaths(clip.first, clip.positions, tuple(k.frame for k in keys))


def _taken(character: Character, local: np.ndarray, root: np.ndarray, targets: list) -> np.ndarray | None:
    """The positions ``(22, 3)`` of the pose ``local (22, 4)``, ``root (3,)`` with the
    active ``targets`` (JointTargets) taken by the limbs and turned joints, as a key or a
    bake's in-between is posed; None when no target moves a limb or turns a joint."""
    from engine.authoring.targets import solve_inputs
    from engine.solver.limb_ik import LIMBS, finish

    _, reach, rotations = solve_inputs(targets)
    limbs = {j: np.asarray(p, float) for j, p in reach.items() if j in LIMBS}
    if not (limbs or rotations):
        return None
    return finish(local, root, character.skeleton.offsets, limbs, dict(rotations))[1]


def key_poses(character: Character, keys: list[Key]) -> tuple[np.ndarray, np.ndarray]:
    """The decoded positions ``(K, 22, 3)`` of keys with a latent and their exact ones
    (the active targets taken by the limbs and turned joints, as a key is posed), metres."""
    latents = [np.asarray(k.latent, np.float32) for k in keys if k.latent is not None]
    if len(latents) != len(keys):
        raise ValueError("key_poses: every key needs a latent")
    local, root, decoded = character.decode_many(
        np.stack(latents), np.stack([k.root for k in keys]), np.array([k.heading for k in keys])
    )
    exact = decoded.copy()
    for i, k in enumerate(keys):
        taken = _taken(character, local[i], root[i], list(k.targets.values()))
        if taken is not None:
            exact[i] = taken
    return decoded, exact


def keyed_paths(
    character: Character, keys: list[Key], scheme: str, constraints: Sequence[Constraint] = ()
) -> MotionPaths | None:
    """A preview of the bake's paths over the keyed range from the keys that have a
    latent, with the scene's ``constraints`` (its pins) as the bake has them (see the
    module doc); None when no key has one."""
    from engine.authoring.bake import interpolated_targets, pinned_key

    rules = list(constraints)
    posed = sorted((pinned_key(k, rules) for k in keys if k.latent is not None), key=lambda k: k.frame)
    if not posed:
        return None
    decoded, exact = key_poses(character, posed)
    times = [float(k.frame) for k in posed]
    first, last = int(times[0]), int(times[-1])
    frames = np.arange(first, last + 1, dtype=float)
    latents = [np.asarray(k.latent, float) for k in posed]
    z = np.stack([interpolate(times, latents, f, scheme) for f in frames])
    xy = np.stack([interpolate(times, [np.asarray(k.root, float) for k in posed], f, scheme) for f in frames])
    unwrapped = np.degrees(np.unwrap(np.radians([k.heading for k in posed])))
    heading = np.array([interpolate(times, [np.array([h]) for h in unwrapped], f, scheme)[0] for f in frames])
    local, root, positions = character.decode_many(z, xy, heading)
    gaps = [(e - d).ravel() for e, d in zip(exact, decoded)]
    out = positions + np.stack([interpolate(times, gaps, f, scheme) for f in frames]).reshape(positions.shape)
    for i, f in enumerate(frames):
        # the bake's in-betweens put the limbs on the interpolated targets exactly
        targets, _ = pinned_targets(interpolated_targets(posed, times, f, scheme), rules, int(f))
        taken = _taken(character, local[i], root[i], targets)
        if taken is not None:
            moved = np.abs(taken - positions[i]).max(axis=1) > 1e-9
            out[i, moved] = taken[moved]
    return MotionPaths(first, out, tuple(k.frame for k in keys), exact=False)


def authored_paths(
    character: Character,
    keys: list[Key],
    scheme: str,
    baked: Baked | None,
    constraints: Sequence[Constraint] = (),
) -> MotionPaths | None:
    """The paths of an authored animation: the bake's when there is one, else the
    preview (:func:`keyed_paths`, with the scene's ``constraints``)."""
    if baked is not None:
        return baked_paths(baked, keys)
    return keyed_paths(character, keys, scheme, constraints)
