"""What an authoring edit saves and restores: the model's state, as immutable copies,
and the poses the model takes on a key or between keys.

:class:`AuthoringState` holds the targets, the planted feet, the pose and facing, the
keys, the animation's length, rate and scheme and the constraint list. An edit records
it before and after (:class:`engine.authoring.history.Edit`); :func:`differences`
compares two of them part by part, so the session announces exactly the parts an edit
or its undo changed. :func:`pose_on_key` and :func:`pose_between` pose the character on
a frame (the session's ``go_to``).
"""

from __future__ import annotations

import copy
from dataclasses import dataclass

import numpy as np

from engine.authoring.bake import Baked, interpolated_heading, interpolated_targets, pinned_key
from engine.authoring.character import Pose
from engine.authoring.document import AuthoringScene
from engine.authoring.keys import Animation, Key
from engine.authoring.pose_mode import PoseMode
from engine.authoring.targets import JointTarget
from engine.constraints.base import Constraint
from engine.kinematics.fk import fk_positions


@dataclass(frozen=True)
class AuthoringState:
    """One moment of the authoring model (copies: nothing here changes afterwards).

    Attributes
    ----------
    targets : tuple of JointTarget
    planted : tuple of (str, ndarray (3,))
        Where each planted foot joint stays, metres.
    pose : Pose
    heading : float
        Facing, degrees about +Z.
    keys : tuple of Key
    animation : (frames, fps, interpolation)
    constraints : tuple of Constraint
        Constraint objects are replaced on every edit, never changed, so they are shared.
    selected : str or None
        The selected joint (its rotation rings shown): no edit in itself, kept with the
        edits so that undo and redo give the rings back to the joint they were on.
    """

    targets: tuple[JointTarget, ...]
    planted: tuple[tuple[str, np.ndarray], ...]
    pose: Pose
    heading: float
    keys: tuple[Key, ...]
    animation: tuple[int, float, str]
    constraints: tuple[Constraint, ...]
    selected: str | None = None

    def animation_object(self) -> Animation:
        frames, fps, interpolation = self.animation
        return Animation(fps=fps, frames=frames, interpolation=interpolation)


def same_target(a: JointTarget | None, b: JointTarget | None) -> bool:
    """Whether two targets (or their absence) are equal in every field."""
    if a is None or b is None:
        return a is b
    rot = (a.rotation is None and b.rotation is None) or (
        a.rotation is not None and b.rotation is not None and np.array_equal(a.rotation, b.rotation)
    )
    return (
        rot
        and np.array_equal(a.position, b.position)
        and a.weight == b.weight
        and a.enabled == b.enabled
        and a.pelvis_only == b.pelvis_only
    )


def same_key(a: Key, b: Key) -> bool:
    """Whether two keys are equal in every field."""
    la, lb = a.latent, b.latent
    latent = (la is None and lb is None) or (la is not None and lb is not None and np.array_equal(la, lb))
    targets = set(a.targets) == set(b.targets) and all(same_target(a.targets[j], b.targets[j]) for j in a.targets)
    feet = set(a.feet) == set(b.feet) and all(np.array_equal(a.feet[j], b.feet[j]) for j in a.feet)
    same = a.frame == b.frame and latent and targets and feet
    return same and np.array_equal(a.root, b.root) and a.heading == b.heading


def same_pose(a: Pose, b: Pose) -> bool:
    return a is b or (
        np.array_equal(a.latent, b.latent)
        and np.array_equal(a.positions, b.positions)
        and np.array_equal(a.local_rot, b.local_rot)
    )


@dataclass(frozen=True)
class Differences:
    """What differs between two states: target joints, key frames (added, removed,
    changed), and whether the pose, the animation, the constraints and the selected
    joint do."""

    joints: tuple[str, ...]
    keys_added: tuple[int, ...]
    keys_removed: tuple[int, ...]
    keys_changed: tuple[int, ...]
    pose: bool
    animation: bool
    constraints: bool
    selection: bool = False

    @property
    def keys(self) -> bool:
        return bool(self.keys_added or self.keys_removed or self.keys_changed)


def differences(old: AuthoringState, new: AuthoringState) -> Differences:
    """Compare ``old`` with ``new`` part by part (see :class:`Differences`)."""
    t_old = {t.joint: t for t in old.targets}
    t_new = {t.joint: t for t in new.targets}
    joints = tuple(j for j in dict.fromkeys([*t_old, *t_new]) if not same_target(t_old.get(j), t_new.get(j)))
    k_old = {k.frame: k for k in old.keys}
    k_new = {k.frame: k for k in new.keys}
    added = tuple(sorted(set(k_new) - set(k_old)))
    removed = tuple(sorted(set(k_old) - set(k_new)))
    changed = tuple(sorted(f for f in set(k_old) & set(k_new) if not same_key(k_old[f], k_new[f])))
    pose = not same_pose(old.pose, new.pose) or old.heading != new.heading
    constraints = len(old.constraints) != len(new.constraints) or any(
        a is not b for a, b in zip(old.constraints, new.constraints)
    )
    animation = old.animation != new.animation
    return Differences(joints, added, removed, changed, pose, animation, constraints, old.selected != new.selected)


def capture(mode: PoseMode, scene: AuthoringScene, selected: str | None = None) -> AuthoringState:
    """The state of ``mode`` (targets, planted feet, pose, facing) and ``scene`` (keys,
    animation, constraints), as copies, with the ``selected`` joint."""
    a = scene.animation
    return AuthoringState(
        tuple(copy.deepcopy(t) for t in mode.targets.values()),
        tuple((j, p.copy()) for j, p in mode.planted.items()),
        mode.pose,
        mode.heading,
        tuple(copy.deepcopy(k) for k in scene.keys),
        (a.frames, a.fps, a.interpolation),
        tuple(mode.constraints),
        selected,
    )


def put(mode: PoseMode, scene: AuthoringScene, state: AuthoringState) -> None:
    """Make ``state`` that of ``mode`` and ``scene`` (copies again: the state stays as it is;
    the constraint list and the animation object are edited in place, as others hold them)."""
    mode.targets = {t.joint: copy.deepcopy(t) for t in state.targets}
    mode.planted = {j: p.copy() for j, p in state.planted}
    mode.pose, mode.heading = state.pose, state.heading
    scene.keys = [copy.deepcopy(k) for k in state.keys]
    a = scene.animation
    a.frames, a.fps, a.interpolation = state.animation
    mode.constraints[:] = list(state.constraints)


def holds_key(mode: PoseMode, key: Key) -> bool:
    """Whether ``mode`` is posed as :func:`pose_on_key` poses it on ``key`` and as
    ``add_key`` keys it: the key's targets and, for a key with a latent, its latent, its
    place and its facing."""
    targets = set(mode.targets) == set(key.targets) and all(
        same_target(mode.targets[j], t) for j, t in key.targets.items()
    )
    if key.latent is None or not targets:
        return targets
    return (
        np.array_equal(mode.pose.latent, key.latent)
        and np.array_equal(mode.standing_place(), key.root)
        and mode.heading == key.heading
    )


def pose_on_key(mode: PoseMode, key: Key) -> None:
    """Pose ``mode`` as ``key``: when it has a latent, its pose as the bake poses it
    (:meth:`~engine.authoring.pose_mode.PoseMode.pose_key`); else its targets on the
    current pose (posing them is a bake's work, too long for a scrub)."""
    if key.latent is not None:
        mode.pose_key(key)
    else:
        mode.targets = copy.deepcopy(key.targets)


def pose_between(mode: PoseMode, baked: Baked, keys: list[Key], scheme: str, frame: int) -> None:
    """Pose ``mode`` as the baked in-between at ``frame``: its latent and pose, the facing
    and targets interpolated there (so a key added on it keeps the motion). The targets
    are interpolated between the keys as the pins on their frames leave them, as the
    bake interpolates them (:func:`engine.authoring.bake.pinned_key`); a pin acting on
    ``frame`` itself wins in every solve of ``mode``
    (:attr:`engine.authoring.pose_solve.PoseSolving.aimed`)."""
    motion = baked.motion
    f = min(int(frame), len(motion) - 1)
    local, root = motion.local_rot[f].copy(), motion.root_pos[f].copy()
    mode.pose = Pose(baked.latents[f].copy(), local, root, fk_positions(local, root, motion.skeleton.offsets))
    times = [float(k.frame) for k in keys]
    mode.heading = interpolated_heading(keys, times, f, scheme)
    pinned = [pinned_key(k, mode.constraints) for k in keys]
    mode.targets = {t.joint: copy.deepcopy(t) for t in interpolated_targets(pinned, times, f, scheme)}
