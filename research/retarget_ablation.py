"""How much of the difference between two copies of a take is a constant offset per joint.

Two converters that place a landmark differently (a knuckle line turned about the hand,
eyes higher on the head, a toe tip lower) give canonical world rotations that differ by a
rotation constant over the clip, ``G_b(t) ~ G_a(t) K_j`` for each joint ``j``; a true
disagreement about the motion varies with time. :func:`offset_ablation` measures both:
it estimates each joint's ``K_j`` (the mean of ``G_a^-1 G_b`` over the clip), removes it
from ``a`` (local rotations ``K_parent^-1 L_a K_j``) and measures what is left, and splits
each ``K_j`` into its twist about the joint's bone and the swing of the bone.
``research/cross_rig.py --ablate`` prints the table of every take on several rigs.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from engine import skeleton as sk
from engine.kinematics import quaternion as Q
from engine.kinematics.fk import fk
from engine.motion.clip import Motion
from engine.motion.joint_stats import joint_axis, twist_deg
from engine.motion.retarget_frames import mean_rotation
from research.retarget_compare import COMMON_HEIGHT, AlignedPair, align_clips


@dataclass
class OffsetAblation:
    """Per-joint split of the difference of two aligned copies (:func:`offset_ablation`).

    Every array is ``(22,)`` in canonical joint order."""

    #: Mean geodesic angle between the local rotations, degrees (as :func:`compare_clips`).
    raw_deg: np.ndarray
    #: The same once each joint's constant world offset ``K_j`` is removed from ``a``, degrees.
    removed_deg: np.ndarray
    #: Signed twist of ``K_j`` about the joint's bone, degrees (``b`` turned from ``a``).
    offset_twist_deg: np.ndarray
    #: Swing of ``K_j`` (the bone's direction turned), degrees.
    offset_swing_deg: np.ndarray
    #: Mean root-relative position error, centimetres, before and after removing the offsets
    #: (both clips' rotations on the canonical skeleton :data:`COMMON_HEIGHT` tall).
    raw_pos_cm: np.ndarray
    removed_pos_cm: np.ndarray


def swing_twist_deg(q: np.ndarray, axis: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Signed twist about unit ``axis`` (3,) and unsigned swing angle of rotations ``q``
    ``(..., 4)``, degrees (``q = swing * twist``)."""
    tw = twist_deg(q, axis)
    twist = Q.from_axis_angle(np.broadcast_to(axis, q.shape[:-1] + (3,)), np.radians(tw))
    swing = Q.mul(q, Q.conjugate(twist))
    return tw, np.degrees(2.0 * np.arccos(np.clip(np.abs(swing[..., 0]), 0.0, 1.0)))


def _relative(local: np.ndarray) -> np.ndarray:
    scale = COMMON_HEIGHT / sk.Skeleton.canonical(1.0).height()
    pos = fk(local, np.zeros(local.shape[:1] + (3,)), sk.Skeleton.canonical(scale).offsets)[0]
    return pos - pos[:, :1]


def offset_ablation(a: Motion, b: Motion, aligned: AlignedPair | None = None) -> OffsetAblation:
    """Align ``a`` to ``b`` (:func:`research.retarget_compare.align_clips`) and split
    their difference into a constant offset per joint and what varies over the clip.

    Parameters
    ----------
    a, b : Motion
        Canonical clips of the same take.
    aligned : AlignedPair or None
        ``align_clips(a, b)`` when the caller has it already (the alignment costs as
        much as the rest); None: aligned here.

    Returns
    -------
    OffsetAblation
        Per-joint raw and offset-removed differences (degrees, centimetres) and the
        twist / swing of each joint's constant offset.
    """
    p = aligned if aligned is not None else align_clips(a, b)
    la, lb = p.local_a, p.local_b
    zeros = np.zeros(la.shape[:1] + (3,))
    ga = fk(la, zeros, sk.REST_OFFSETS)[1]
    gb = fk(lb, zeros, sk.REST_OFFSETS)[1]
    n = len(la)
    k = np.stack([mean_rotation(Q.mul(Q.conjugate(ga[:, j]), gb[:, j]), np.ones(n)) for j in range(sk.NUM_JOINTS)])
    fixed = la.copy()
    for j in range(sk.NUM_JOINTS):
        left = Q.conjugate(k[sk.PARENTS[j]]) if j > 0 else np.array([1.0, 0.0, 0.0, 0.0])
        fixed[:, j] = Q.mul(
            Q.mul(np.broadcast_to(left, la[:, j].shape), la[:, j]), np.broadcast_to(k[j], la[:, j].shape)
        )
    twist, swing = np.zeros(sk.NUM_JOINTS), np.zeros(sk.NUM_JOINTS)
    for j, name in enumerate(sk.JOINT_NAMES):
        twist[j], swing[j] = (float(v) for v in swing_twist_deg(k[j], joint_axis(name)))
    rb = _relative(lb)
    return OffsetAblation(
        raw_deg=np.degrees(Q.angle(la, lb)).mean(0),
        removed_deg=np.degrees(Q.angle(fixed, lb)).mean(0),
        offset_twist_deg=twist,
        offset_swing_deg=swing,
        raw_pos_cm=100.0 * np.linalg.norm(_relative(la) - rb, axis=-1).mean(0),
        removed_pos_cm=100.0 * np.linalg.norm(_relative(fixed) - rb, axis=-1).mean(0),
    )
