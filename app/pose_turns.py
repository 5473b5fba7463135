"""Turning joints in the pose window: the rotation rings of the selected joint, Alt-drag,
*hold turn*, and the handles drawn (rings, the facing arrow in front of the head).

The mouse gestures are read here and the turn they ask for is computed by
:mod:`engine.authoring.turns`; each becomes one model edit
(:meth:`engine.authoring.session.AuthoringSession.turn_joint`, a rotation target on the
joint, or :meth:`~engine.authoring.session.AuthoringSession.turn_body` for the hips'
ring about the vertical).
"""

from __future__ import annotations

import time
from typing import Any

import numpy as np

from engine import skeleton as sk
from engine.authoring.turns import SweptTurn, ring_turn
from engine.kinematics import quat_np as QN

#: How the status bar names a ring while it is dragged (world X, Y, Z).
RING_NAMES = ("X (red ring)", "Y (green ring)", "Z (blue ring)")
#: How long a turn's readout stays after the last mouse move, milliseconds.
READOUT_MS = 4000


def turn_readout(joint: str, axis: int, angle_deg: float) -> str:
    """The status bar's line while ``joint``'s ring about world ``axis`` is dragged by
    ``angle_deg`` degrees since the press (whole degrees, or 5-degree steps with Ctrl:
    :func:`widgets.viewport.rings.snapped`): what a user reads to turn a head 60 degrees.
    About Z, a positive angle turns a body facing the front view to its left."""
    side = " (to its left)" if axis == 2 and angle_deg > 0 else " (to its right)" if axis == 2 and angle_deg < 0 else ""
    return f"Turn {joint} about {RING_NAMES[axis]}: {angle_deg:+.0f} deg{side}; Ctrl: 5-deg steps"


class JointTurns:
    """The turning of joints of the pose window ``w`` (see the module doc)."""

    def __init__(self, w: Any) -> None:
        self.w = w
        self.gesture: SweptTurn | None = None  # the Alt-drag going on
        self._ring_start: tuple | None = None  # the turned joint's world rotation (or facing) at the press

    def world_rotation(self, joint: str) -> np.ndarray:
        """The current pose's world rotation ``(4,)`` of ``joint``."""
        return self.w.session.world_rotation(joint)

    def by_ring(self, axis: int, angle: float, first: bool) -> None:
        """A rotation ring of the selected joint dragged by ``angle`` radians about world
        axis ``axis`` since the press (``first``: the press itself)."""
        joint = self.w.selected
        if joint is None:
            return
        if first:
            self._ring_start = (self.w.mode.heading,) if joint == "root" else (self.world_rotation(joint),)
            return
        if self._ring_start is None:
            return
        shown = "the body" if joint == "root" else joint
        self.w.statusBar().showMessage(turn_readout(shown, axis, float(np.degrees(angle))), READOUT_MS)
        if joint == "root":
            if axis == 2:
                self.w.turn_body(self._ring_start[0] + np.degrees(angle))
            return
        q = ring_turn(self._ring_start[0], axis, angle)
        self.w._edit(lambda: self.w.session.turn_joint(joint, q))

    def alt_drag(self, joint: str, position: np.ndarray) -> None:
        """Alt + drag to ``position (3,)`` metres on the drag plane: turn ``joint``
        (:class:`engine.authoring.turns.SweptTurn`) about its target, or itself."""
        t = self.w.mode.targets.get(joint)
        pivot = t.position if t is not None else self.w.mode.pose.positions[sk.JOINT_INDEX[joint]]
        g = self.gesture = SweptTurn.follow(self.gesture, joint, self.world_rotation(joint), time.monotonic())
        q = g.rotation(np.asarray(position, float) - pivot)
        if q is not None:
            self.w._edit(lambda: self.w.session.turn_joint(joint, q))
        g.last = time.monotonic()  # a pause is the mouse's, not the solve's: a slow solve keeps the gesture

    def hold(self, joint: str, on: bool) -> None:
        """Give the target on ``joint`` the joint's current world rotation (``on``) or
        make it a position target again."""
        self.w._edit(lambda: self.w.session.hold_turn(joint, on))

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
