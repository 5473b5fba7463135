"""Pose mode's hold (``PoseOptions.hold_weight``): the joints no target holds are pulled
towards where they stood in the pose the drag began from (the anchor,
:attr:`engine.authoring.pose_mode.PoseMode.anchor`), relative to the root.

:func:`held_joints` says which joints the hold pulls; :func:`hold_terms` makes its
targets for a solve with the root at a given place.
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
