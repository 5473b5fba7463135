"""``pin``: a joint stays where it was.

Its default weight is 30, not 1: a pin is the user overriding the trackers, and at
weight 1 six sensor terms of the same scale (squared metres) held a Ctrl-dragged elbow
10-13 cm short of the pin with the shipped DragPoser; at 30 it pulls the joint in over
a few frames and holds it within ~2 cm; ``research/measure_pin.py`` measures it
(docs/studio.md, "Pins").

With ``follow_previous`` the target is the joint's previous-frame position every frame
(the joint resists motion). Otherwise the target is ``position``; while that is unset
(NaN) the target is the previous frame's solved position, and a method keeps it from the
first frame that has one on (:meth:`PinConstraint.settled` returns the captured copy;
the pin itself is never changed). On the very first frame, with no previous pose, an
unset pin costs nothing.

Residual: ``P_j - t``.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from typing import Any, ClassVar

import numpy as np

from engine.constraints.base import Constraint, OnOneJoint, joint_index, param
from engine.constraints.placement import joint_at
from engine.constraints.residual import FrameInputs, PointTerm
from engine.gizmos import PointGizmo


@dataclass
class PinConstraint(OnOneJoint, Constraint):
    """Keep ``joint`` at ``position`` (metres), see the module doc."""

    kind: ClassVar[str] = "pin"
    weight: float = 30.0
    joint: str = param("lankle", editor="joint")
    position: np.ndarray = param(factory=lambda: np.full(3, np.nan), editor="vec3", unit="m")
    follow_previous: bool = param(False, editor="bool")
    tolerance: float = param(0.01, editor="float", unit="m")

    def _target(self, previous: Any) -> Any:
        """The target (same type as ``previous``'s rows), or None while there is none."""
        j = joint_index(self.joint, "joint", self.kind)
        if self.follow_previous and previous is not None:
            return previous[j]
        if np.all(np.isfinite(self.position)):
            return self.position
        return None if previous is None else previous[j]

    def settled(self, previous_positions: np.ndarray | None) -> "PinConstraint":
        """A copy holding the previous pose's joint position when ``position`` is unset."""
        if self.follow_previous or previous_positions is None or np.all(np.isfinite(self.position)):
            return self
        j = joint_index(self.joint, "joint", self.kind)
        return dataclasses.replace(self, position=np.array(previous_positions[j], dtype=np.float64))

    def term(self, frame: FrameInputs) -> PointTerm:
        """``on * (P_j - target)``: ``on`` 0 while there is no target (module doc)."""
        target = self._target(frame.previous_positions)
        j = joint_index(self.joint, "joint", self.kind)
        term = PointTerm(self.name, (j,), np.zeros(3) if target is None else target, float(target is not None))
        term.check_group, term.check_limit2 = np.zeros(3, dtype=np.intp), np.array([self.tolerance**2])  # off: r = 0
        return term

    @classmethod
    def examples(cls, positions: np.ndarray) -> list[Constraint]:
        return [
            cls(joint="rwrist", position=positions[joint_index("rwrist")] + [0.0, -0.1, 0.05]),
            cls(name="follow", joint="lelbow", follow_previous=True),
            cls(name="unset", joint="rknee"),
        ]

    @classmethod
    def placement(cls, params: dict[str, Any], positions: np.ndarray) -> dict[str, Any]:
        """Pinned where the joint is now."""
        return {"position": joint_at(positions, params.get("joint"), "lankle")}

    def gizmo(self, positions: np.ndarray | None = None) -> PointGizmo | None:
        """A draggable point labelled with the joint, tied to the joint by a line."""
        if not np.all(np.isfinite(self.position)):
            return None
        anchor = None
        if positions is not None:
            anchor = np.asarray(positions, float)[joint_index(self.joint, "joint", self.kind)]
        return PointGizmo(self.position, edit="position", label=self.joint, anchor=anchor)
