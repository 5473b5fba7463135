"""Pose mode's holds, pulls towards the pose the drag began from (the anchor,
:attr:`engine.authoring.pose_mode.PoseMode.anchor`).

The hold (``PoseOptions.hold_weight``) pulls the joints no target holds towards where
they stood relative to the root: :func:`held_joints` says which, :func:`hold_terms` makes
its targets for a solve with the root at a given place. The free-arm hold
(``PoseOptions.free_arm_weight``) keeps an arm no target holds hanging as it hung from
its shoulder while another arm is dragged: :func:`free_arms` says which arms,
:func:`free_arm_terms` makes its targets.
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np

from engine import skeleton as sk
from engine.authoring.character import Pose
from engine.authoring.pose_root import FOOT_OF, moved_feet
from engine.authoring.targets import JointTarget
from engine.constraints.base import Constraint
from engine.solver.limb_ik import LIMBS


def held_joints(targets: Mapping[str, JointTarget], planted: Mapping[str, np.ndarray], plant_feet: bool) -> list[int]:
    """Joints the hold pulls towards the anchor: every joint but the root, the joints
    with a target in ``targets``, the ``planted`` feet (with ``plant_feet``), and the
    knee or elbow and toe of a targeted limb (the limb step places those)."""
    free = {0} | {t.index for t in targets.values() if t.active}
    for t in targets.values():
        if t.active and t.index in LIMBS:
            free.add(LIMBS[t.index][1])
            if t.joint in FOOT_OF:
                free.add(sk.JOINT_INDEX[FOOT_OF[t.joint] + "toe"])
    if plant_feet:
        moved = moved_feet(targets)
        free |= {sk.JOINT_INDEX[j] for j in planted if FOOT_OF[j] not in moved}
    return [j for j in range(len(sk.JOINT_NAMES)) if j not in free]


def hold_terms(anchor: Pose, held: list[int], where: np.ndarray, weight: float) -> list[Constraint]:
    """The hold's terms, each of ``weight``, for a solve with the root at ``where (3,)``
    metres: each ``held`` joint's ``anchor`` position relative to the anchor's root, from
    ``where``."""
    a = anchor
    return [
        JointTarget(sk.JOINT_NAMES[j], a.positions[j] - a.root_pos + where, weight=weight).constraint() for j in held
    ]


#: Each arm's joints (clavicle, shoulder, elbow, wrist) for the free-arm hold
#: (``PoseOptions.free_arm_weight``).
ARMS = {side: tuple(sk.JOINT_INDEX[f"{side}{j}"] for j in ("clavicle", "shoulder", "elbow", "wrist")) for side in "lr"}
#: Joints whose targets leave the trunk where it stands: the arms' and the head's. A
#: target elsewhere (the pelvis, a leg) moves the body, and the free arms go with it as
#: the prior moves them.
ARM_DRAGS = frozenset(j for arm in ARMS.values() for j in arm) | {
    sk.JOINT_INDEX["lowerneck"],
    sk.JOINT_INDEX["upperneck"],
}
#: Metres above the lowest point an arm reaches hanging from the standing shoulder below
#: which a wrist target lets the free arms go: a reach that far down the body bends the
#: trunk, and a free arm held during its first events left the hand-to-knee reach 0.2 cm
#: further from the knee and 0.5 cm further from a real pose (``bench --pose-tasks``).
FREE_ARM_LOW = 0.20


def arm_reach(targets: Mapping[str, JointTarget], hanging: Mapping[int, float]) -> bool:
    """Whether every active target of ``targets`` is on an arm or the head
    (:data:`ARM_DRAGS`) and no wrist target lies lower than :data:`FREE_ARM_LOW` above
    ``hanging`` (per wrist, the lowest height its arm reaches hanging from the standing
    shoulder): a reach the arms make, which leaves the legs and the pelvis as they stand."""
    active = [t for t in targets.values() if t.active]
    if any(t.index not in ARM_DRAGS for t in active):
        return False
    return not any(t.index in hanging and t.position[2] < hanging[t.index] + FREE_ARM_LOW for t in active)


def free_arms(
    targets: Mapping[str, JointTarget], hanging: Mapping[int, float], plant_feet: bool
) -> list[tuple[int, ...]]:
    """The arms (joint indices, :data:`ARMS`) the free-arm hold keeps: those on which no
    active target lies, while the feet are planted (``plant_feet``), every active target
    is on an arm or the head (:data:`ARM_DRAGS`) and no wrist target lies lower than
    :data:`FREE_ARM_LOW` above ``hanging`` (per wrist, the lowest height its arm reaches
    hanging from the standing shoulder). None otherwise: the trunk moves, and the free
    arms move with it as the prior has them."""
    if not plant_feet or not arm_reach(targets, hanging):
        return []
    busy = {t.index for t in targets.values() if t.active}
    return [arm for arm in ARMS.values() if not busy & set(arm)]


def free_arm_terms(
    anchor: Pose, pose: Pose, arms: list[tuple[int, ...]], where: np.ndarray, weight: float
) -> list[Constraint]:
    """Terms, each of ``weight``, that hold the elbow and wrist of each of ``arms`` where
    they hung in ``anchor`` from its shoulder, from where that shoulder is in ``pose``
    (the pose a solve starts from) with its root moved to ``where (3,)``: the arm keeps
    its world direction, as a hanging arm does, and goes with its shoulder when the body
    moves (a reach's balance step, a lean)."""
    shift = np.asarray(where, float) - pose.root_pos
    out: list[Constraint] = []
    for _, shoulder, elbow, wrist in arms:
        at = pose.positions[shoulder] + shift
        for j in (elbow, wrist):
            goal = at + anchor.positions[j] - anchor.positions[shoulder]
            out.append(JointTarget(sk.JOINT_NAMES[j], goal, weight=weight).constraint())
    return out
