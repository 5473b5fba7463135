"""A pelvis-only drag: the hips move, the feet stay planted, the upper body rides along.

Shift + drag on the hips in the pose window (the pelvis move of Cascadeur and Blender's
rigs): the pelvis goes where it is dragged and keeps its turn; the spine, arms and head
keep their pose relative to it (their local rotations are unchanged); each planted leg
reaches its ankle back to where it stood by its two bones
(:func:`engine.solver.limb_ik.reach_local`, which bends the knee in its own plane and
keeps the ankle's world rotation), and the ankle is then turned so its toe is back on
its place too: the foot stays flat where it stood. Targeted wrists are put back on their
targets by their arms where they reach.

The pose's latent is left as it was: it describes the body standing where it stood (the
pose's ``decoded`` positions), and :func:`pelvis_pose` is applied on it again after every
solve while the root's target asks for it (``JointTarget.pelvis_only``); so a key made
with such a drag is baked to the same pose.
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np

from engine import skeleton as sk
from engine.authoring.character import Pose
from engine.kinematics.fk import fk
from engine.kinematics.quat_np import qbetween, qconj, qmul
from engine.solver.limb_ik import LIMBS, reach_local

#: The joints of both legs whose local rotations the legs bend from.
LEG_JOINTS = tuple(sk.JOINT_INDEX[s + n] for s in "lr" for n in ("hip", "knee", "ankle"))
#: A planted leg is kept this far (metres) short of fully straight, so its knee still bends.
STRAIGHT_MARGIN = 0.002
#: Halvings of the way back to the pelvis's place when the legs cannot reach a dragged one.
SEARCH_STEPS = 30


def legs_reach(pose: Pose, pelvis: np.ndarray, feet: Mapping[str, np.ndarray]) -> bool:
    """Whether every planted leg of ``pose`` (its ankle at ``feet[ankle]`` (3,) metres)
    reaches its ankle with the pelvis moved to ``pelvis (3,)`` metres, turned as it is."""
    shift = np.asarray(pelvis, float) - pose.root_pos
    for ankle, _ in sk.FEET.values():
        if ankle not in feet:
            continue
        hip, knee = LIMBS[sk.JOINT_INDEX[ankle]]
        p = pose.positions
        length = np.linalg.norm(p[knee] - p[hip]) + np.linalg.norm(p[sk.JOINT_INDEX[ankle]] - p[knee])
        if np.linalg.norm(p[hip] + shift - feet[ankle]) > length - STRAIGHT_MARGIN:
            return False
    return True


def within_legs(pose: Pose, pelvis: np.ndarray, feet: Mapping[str, np.ndarray]) -> np.ndarray:
    """``pelvis (3,)`` metres, or where the legs still reach on the way to it from the
    pose's pelvis (:func:`legs_reach`): a pelvis dragged higher or further than the
    planted legs reach stops where they are nearly straight."""
    goal = np.asarray(pelvis, float)
    if legs_reach(pose, goal, feet):
        return goal
    if not legs_reach(pose, pose.root_pos, feet):
        return pose.root_pos.copy()
    lo, hi = 0.0, 1.0
    for _ in range(SEARCH_STEPS):
        mid = (lo + hi) / 2
        if legs_reach(pose, pose.root_pos + mid * (goal - pose.root_pos), feet):
            lo = mid
        else:
            hi = mid
    return pose.root_pos + lo * (goal - pose.root_pos)


def pelvis_pose(
    pose: Pose,
    pelvis: np.ndarray,
    feet: Mapping[str, np.ndarray],
    offsets: np.ndarray,
    limbs: Mapping[int, np.ndarray],
    legs: np.ndarray | None = None,
) -> Pose:
    """``pose`` with the pelvis at ``pelvis (3,)`` metres (see the module doc).

    Parameters
    ----------
    feet : mapping foot joint -> ndarray (3,)
        Where the planted ankles and toes stay, metres (a leg whose ankle is missing is
        carried with the pelvis).
    offsets : ndarray (22, 3)
        The skeleton's bone offsets.
    limbs : mapping joint index -> ndarray (3,)
        Targets of wrists and ankles the limbs reach for (an ankle's target wins over
        its planted place; its toe then goes where the foot's turn takes it).
    legs : ndarray (22, 4) or None
        Local rotations whose :data:`LEG_JOINTS` rows the legs bend from (the latent's
        own: then the result does not depend on the way the pelvis took, since the two
        bones' step keeps the plane it starts in); None: ``pose``'s.

    Returns
    -------
    Pose
        The latent and ``decoded`` positions of ``pose``; the root at ``pelvis``.
    """
    root = np.asarray(pelvis, float).copy()
    ankles = {sk.JOINT_INDEX[a]: np.asarray(feet[a], float) for a, _ in sk.FEET.values() if a in feet}
    reach = {**ankles, **{j: np.asarray(p, float) for j, p in limbs.items() if j in LIMBS}}
    local = np.array(pose.local_rot, float)
    if legs is not None:
        local[list(LEG_JOINTS)] = np.asarray(legs, float)[list(LEG_JOINTS)]
    local = reach_local(local, root, offsets, reach)
    local, positions = toes_on(local, root, offsets, {j: p for j, p in feet.items() if j.endswith("toe")}, limbs)
    decoded = None if pose.decoded is None else pose.decoded.copy()
    return Pose(pose.latent.copy(), local, root, positions, pose.iterations, decoded)


def toes_on(
    local: np.ndarray,
    root: np.ndarray,
    offsets: np.ndarray,
    toes: Mapping[str, np.ndarray],
    limbs: Mapping[int, np.ndarray] | None = None,
) -> tuple[np.ndarray, np.ndarray]:
    """Local rotations ``local (22, 4)`` with each ankle turned (the shortest turn) so its
    toe joint is on its place in ``toes`` (toe joint name -> (3,) metres; a foot whose
    ankle has a target in ``limbs``, joint index -> place, is left as it is), and the
    world positions ``(22, 3)`` of the result: a planted foot stays flat where it stood."""
    local = np.array(local, float)
    positions, world = fk(local, root, offsets)
    for ankle, toe in sk.FEET.values():
        a, t = sk.JOINT_INDEX[ankle], sk.JOINT_INDEX[toe]
        if toe not in toes or a in (limbs or {}):
            continue
        have, want = positions[t] - positions[a], np.asarray(toes[toe], float) - positions[a]
        turned = qmul(qbetween(tuple(have), tuple(want)), tuple(world[a]))
        local[a] = qmul(qconj(tuple(world[sk.PARENTS[a]])), turned)
    local *= np.where(local[:, :1] < 0, -1.0, 1.0)
    return local, fk(local, root, offsets)[0]
