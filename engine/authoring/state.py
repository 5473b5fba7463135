"""What an authoring edit saves and restores: the model's state, as immutable copies.

:class:`AuthoringState` holds the targets, the planted feet, the pose and facing, the
keys, the animation's length, rate and scheme and the constraint list. An edit records
it before and after (:class:`engine.authoring.history.Edit`); :func:`differences`
compares two of them part by part, so the session announces exactly the parts an edit
or its undo changed.
"""

from __future__ import annotations

import copy
from dataclasses import dataclass

import numpy as np

from engine.authoring.character import Pose
from engine.authoring.keys import Animation, Key
from engine.authoring.targets import JointTarget
from engine.constraints.base import Constraint


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
    """

    targets: tuple[JointTarget, ...]
    planted: tuple[tuple[str, np.ndarray], ...]
    pose: Pose
    heading: float
    keys: tuple[Key, ...]
    animation: tuple[int, float, str]
    constraints: tuple[Constraint, ...]

    def animation_object(self) -> Animation:
        frames, fps, interpolation = self.animation
        return Animation(fps=fps, frames=frames, interpolation=interpolation)


def same_target(a: JointTarget | None, b: JointTarget | None) -> bool:
    """Whether two targets (or their absence) are equal in every field."""
    if a is None or b is None:
        return a is b
    rot = (a.rotation is None and b.rotation is None) or (
        a.rotation is not None and b.rotation is not None and np.array_equal(a.rotation, b.rotation))
    return rot and np.array_equal(a.position, b.position) and a.weight == b.weight and a.enabled == b.enabled


def same_key(a: Key, b: Key) -> bool:
    """Whether two keys are equal in every field."""
    la, lb = a.latent, b.latent
    latent = (la is None and lb is None) or (la is not None and lb is not None and np.array_equal(la, lb))
    targets = set(a.targets) == set(b.targets) and all(same_target(a.targets[j], b.targets[j]) for j in a.targets)
    return (a.frame == b.frame and latent and targets and np.array_equal(a.root, b.root)
            and a.heading == b.heading)  # fmt: skip


def same_pose(a: Pose, b: Pose) -> bool:
    return a is b or (np.array_equal(a.latent, b.latent) and np.array_equal(a.positions, b.positions)
                      and np.array_equal(a.local_rot, b.local_rot))  # fmt: skip


@dataclass(frozen=True)
class Differences:
    """What differs between two states: target joints, key frames (added, removed,
    changed), and whether the pose, the animation and the constraints do."""

    joints: tuple[str, ...]
    keys_added: tuple[int, ...]
    keys_removed: tuple[int, ...]
    keys_changed: tuple[int, ...]
    pose: bool
    animation: bool
    constraints: bool

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
        a is not b for a, b in zip(old.constraints, new.constraints))
    return Differences(joints, added, removed, changed, pose, old.animation != new.animation, constraints)


def copy_targets(targets: dict[str, JointTarget]) -> tuple[JointTarget, ...]:
    return tuple(copy.deepcopy(t) for t in targets.values())
