"""Turning joints in the pose window: the rotation rings of the selected joint, Alt-drag
(a turn by the angle the mouse sweeps about the joint), *hold turn*, and the handles
drawn (rings, the facing arrow in front of the head).

Every turn is a rotation target on the joint (its world rotation), one undo step of the
window (:meth:`app.pose_window.PoseWindow.edit`); on the hips, the ring about the
vertical turns the whole body (:meth:`app.pose_window.PoseWindow.turn_body`).
"""

from __future__ import annotations

import time
from typing import Any

import numpy as np

from engine import skeleton as sk
from engine.kinematics import quat_np as QN
from engine.kinematics import quaternion as Q
from engine.kinematics.fk import fk

#: Alt + drag: the mouse must be this far from the joint (metres, on the drag plane)
#: before its direction starts turning the joint (closer, the direction is noise).
TURN_START_M = 0.02
#: A pause longer than this (seconds) between Alt-drag moves starts a new turn.
TURN_GESTURE_S = 0.5


class JointTurns:
    """The turning of joints of the pose window ``w`` (see the module doc)."""

    def __init__(self, w: Any) -> None:
        self.w = w
        self.gesture: list | None = None  # Alt-drag: joint, start direction, start rotation, last time
        self._ring_start: tuple | None = None  # the turned joint's world rotation (or facing) at the press

    def world_rotation(self, joint: str) -> np.ndarray:
        """The current pose's world rotation ``(4,)`` of ``joint``."""
        p = self.w.mode.pose
        return fk(p.local_rot, p.root_pos, self.w.mode.character.skeleton.offsets)[1][sk.JOINT_INDEX[joint]]

    def by_ring(self, axis: int, angle: float, first: bool) -> None:
        """A rotation ring of the selected joint dragged: turn the joint (a rotation
        target: its rotation at the press turned by ``angle`` radians about world axis
        ``axis``); the hips' ring about Z turns the whole body (its facing)."""
        joint = self.w.selected
        if joint is None:
            return
        if first:
            self._ring_start = (self.w.mode.heading,) if joint == "root" else (self.world_rotation(joint),)
            return
        if self._ring_start is None:
            return
        if joint == "root":
            if axis == 2:
                self.w.turn_body(self._ring_start[0] + np.degrees(angle))
            return
        q = QN.mul(QN.from_axis_angle(np.eye(3)[axis], np.array(angle)), self._ring_start[0])
        self.w.edit(f"turn {joint}", lambda: self.w.mode.set_target(joint, rotation=q / np.linalg.norm(q)),
                    ("target", joint, "rotation"), solve=True)  # fmt: skip

    def alt_drag(self, joint: str, position: np.ndarray) -> None:
        """Alt + drag: give ``joint`` a rotation target, its rotation at the start of the
        drag turned by the rotation carrying the first mouse direction from the joint
        onto the current one (both on the drag plane, ``position (3,)`` metres)."""
        j = sk.JOINT_INDEX[joint]
        t = self.w.mode.targets.get(joint)
        pivot = t.position if t is not None else self.w.mode.pose.positions[j]
        v = np.asarray(position, float) - pivot
        now = time.monotonic()
        g = self.gesture
        if g is None or g[0] != joint or now - g[3] > TURN_GESTURE_S:
            g = self.gesture = [joint, None, self.world_rotation(joint), now]
        g[3] = now
        if g[1] is None:
            if np.linalg.norm(v) >= TURN_START_M:
                g[1] = v
            return
        q = QN.mul(Q.from_to(g[1], v), g[2])
        self.w.edit(f"turn {joint}", lambda: self.w.mode.set_target(joint, rotation=q / np.linalg.norm(q)),
                    ("target", joint, "rotation"), solve=True)  # fmt: skip
        self.gesture = g  # the edit's refresh does not end the gesture

    def hold(self, joint: str, on: bool) -> None:
        """Give the target on ``joint`` the joint's current world rotation (``on``) or
        make it a position target again."""

        def change() -> None:
            if on:
                self.w.mode.set_target(joint, rotation=self.world_rotation(joint))
            else:
                self.w.mode.clear_rotation(joint)

        self.w.edit(f"{'hold' if on else 'free'} turn {joint}", change, solve=True)

    def show_handles(self) -> None:
        """The selected joint's rotation rings (only the turn about Z on the hips: the
        body's facing) and the facing arrow in front of the head."""
        pos = self.w.mode.pose.positions
        rings = self.w.viewport.rings
        if self.w.selected is None or self.w.selected not in sk.JOINT_INDEX:
            rings.hide()
        elif self.w.selected == "root":
            rings.show(pos[0], 0.3, (2,))
        else:
            rings.show(pos[sk.JOINT_INDEX[self.w.selected]], 0.12)
        head = sk.JOINT_INDEX["upperneck"]
        rings.show_facing(pos[head], QN.rotate(self.world_rotation("upperneck"), np.array([0.0, -1.0, 0.0])))
