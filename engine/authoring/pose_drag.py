"""A joint's target dragged as the pose window drags it: in equal steps, a solve on each.

The pose window (``app/pose_window.py``, ``drag_joint``) moves a target and solves on
every mouse move, so where a drag ends depends on the way there, not only on the goal.
:func:`drag` is that drag done headlessly, for any poser with ``targets``, ``pose``,
``set_target`` and ``solve`` (:class:`engine.authoring.pose_mode.PoseMode`, and the
benchmark's :class:`engine.authoring.ik_poser.IKPoser`): the benchmark's tasks and a
baked key's targets (:meth:`engine.authoring.pose_mode.PoseMode.pose_key`) are posed by it.
"""

from __future__ import annotations

import numpy as np

from engine import skeleton as sk
from engine.kinematics import quat_np as QN
from engine.kinematics.fk import fk
from engine.progress import CancelCheck, check

#: Drag events (mouse moves, each a solve) per drag: what the benchmark and the bake use.
EVENTS = 20


def drag(
    poser,
    joint: str,
    offsets: np.ndarray,
    position: np.ndarray | None = None,
    rotation: np.ndarray | None = None,
    events: int = EVENTS,
    weight: float | None = None,
    solve: dict | None = None,
    cancelled: CancelCheck | None = None,
) -> None:
    """Drag ``joint``'s target to ``position (3,)`` metres (from where its target, else the
    joint, is) or turn it to the world ``rotation (4,)`` (from the joint's world rotation,
    the whole turn in equal powers; the target keeps its position), in ``events`` steps,
    calling ``poser.solve(**solve)`` after each.

    ``offsets (22, 3)`` is the poser's skeleton; ``weight`` the target's weight (None: as
    it is, 1 for a new target); ``cancelled()`` is asked before each step (a True answer
    raises :class:`engine.progress.Cancelled`).
    """
    kwargs = solve or {}
    weighed = {} if weight is None else {"weight": weight}
    if rotation is not None:
        start = fk(poser.pose.local_rot, poser.pose.root_pos, offsets)[1][sk.JOINT_INDEX[joint]]
        turn = QN.mul(np.asarray(rotation, float), QN.conjugate(start))  # the whole turn, world frame
        for k in range(1, events + 1):
            check(cancelled)
            poser.set_target(joint, rotation=QN.mul(np.array(QN.qpow(turn, k / events)), start), **weighed)
            poser.solve(**kwargs)
        return
    old = poser.targets.get(joint)
    start = old.position.copy() if old is not None else poser.pose.positions[sk.JOINT_INDEX[joint]].copy()
    goal = np.asarray(position, float)
    for k in range(1, events + 1):
        check(cancelled)
        poser.set_target(joint, start + (goal - start) * k / events, **weighed)
        poser.solve(**kwargs)
