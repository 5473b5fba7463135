"""Turning a joint by hand: the rotation a ring drag or an Alt-drag asks of a joint.

Every turn is a rotation target on the joint (its world rotation, w x y z). A rotation
ring turns the joint's rotation at the press about one world axis by the angle swept;
an Alt-drag turns it by the rotation carrying the first mouse direction from the joint
onto the current one (:class:`SweptTurn`, which also decides when a gesture starts
and ends). Pure functions of numpy arrays: the pose window's mouse handling calls them
and gives the answer to :class:`engine.authoring.session.AuthoringSession`.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from engine import skeleton as sk
from engine.authoring.character import Pose
from engine.kinematics import quat_np as QN
from engine.kinematics import quaternion as Q
from engine.kinematics.fk import fk

#: Alt + drag: the mouse must be this far from the joint (metres, on the drag plane)
#: before its direction starts turning the joint (closer, the direction is noise).
TURN_START_M = 0.02
#: A pause longer than this (seconds) between Alt-drag moves starts a new turn.
TURN_GESTURE_S = 0.5
#: An Alt-drag turns nothing until the mouse's direction from the joint has swept this
#: many degrees (a drag straight away from the joint asks for no turn, and a rotation
#: target equal to the joint's own would show "+rotation" and change nothing).
TURN_MIN_DEG = 2.0


def world_rotation(pose: Pose, offsets: np.ndarray, joint: str) -> np.ndarray:
    """The world rotation ``(4,)`` of ``joint`` in ``pose`` on a skeleton of ``offsets (22, 3)`` m."""
    return fk(pose.local_rot, pose.root_pos, offsets)[1][sk.JOINT_INDEX[joint]]


def ring_turn(start: np.ndarray, axis: int, angle: float) -> np.ndarray:
    """The unit rotation ``(4,)``: ``start (4,)`` turned by ``angle`` radians about world
    axis ``axis`` (0 x, 1 y, 2 z)."""
    q = QN.mul(QN.from_axis_angle(np.eye(3)[axis], np.array(angle)), np.asarray(start, float))
    return q / np.linalg.norm(q)


@dataclass
class SweptTurn:
    """One Alt-drag gesture on ``joint``: its world rotation at the start and the first
    mouse direction far enough from the joint (None until there is one)."""

    joint: str
    start: np.ndarray
    last: float
    direction: np.ndarray | None = None
    turned: bool = False  # the sweep has reached TURN_MIN_DEG once

    @classmethod
    def follow(cls, gesture: SweptTurn | None, joint: str, start: np.ndarray, now: float) -> SweptTurn:
        """The gesture a move at time ``now`` (seconds) belongs to: ``gesture`` going on,
        or a new one from the joint's rotation ``start (4,)`` (another joint, or a pause
        longer than :data:`TURN_GESTURE_S`)."""
        if gesture is None or gesture.joint != joint or now - gesture.last > TURN_GESTURE_S:
            gesture = cls(joint, np.asarray(start, float).copy(), now)
        gesture.last = now
        return gesture

    def rotation(self, offset: np.ndarray) -> np.ndarray | None:
        """The joint's turned rotation ``(4,)`` for the mouse at ``offset (3,)`` metres from
        the joint (on the drag plane); None while the gesture has no direction yet or
        has not turned :data:`TURN_MIN_DEG` yet."""
        v = np.asarray(offset, float)
        if self.direction is None:
            if np.linalg.norm(v) >= TURN_START_M:
                self.direction = v
            return None
        if not self.turned:
            cos = float(self.direction @ v) / max(float(np.linalg.norm(self.direction) * np.linalg.norm(v)), 1e-12)
            if np.degrees(np.arccos(np.clip(cos, -1.0, 1.0))) < TURN_MIN_DEG:
                return None
            self.turned = True
        q = QN.mul(Q.from_to(self.direction, v), self.start)
        return q / np.linalg.norm(q)
