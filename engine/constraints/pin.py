"""``pin``: a joint stays where it was.

Its default weight is 30, not 1: a pin is the user overriding the trackers, and at
weight 1 six sensor terms of the same scale (squared metres) held a Ctrl-dragged elbow
10-13 cm short of the pin with the shipped DragPoser; at 30 it pulls the joint in over
a few frames and holds it within ~2 cm; ``scripts/measure_pin.py`` measures it
(docs/studio.md, "Pins").

With ``follow_previous`` the target is the joint's previous-frame position every frame
(the joint resists motion). Otherwise the target is ``position``; while that is unset
(NaN) the target is the previous frame's solved position, and a method keeps it from the
first frame that has one on (:meth:`PinConstraint.settled` returns the captured copy;
the pin itself is never changed). On the very first frame, with no previous pose, an
unset pin costs nothing.

Fast path: ``|P_j - t|^2`` has gradient ``2 (P_j - t)``.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from typing import Any, ClassVar, TYPE_CHECKING

import numpy as np

from engine.constraints.base import Constraint, joint_index, param, vec
from engine.constraints.placement import joint_at
from engine.constraints.terms import FrameInputs
from engine.gizmos import PointGizmo

if TYPE_CHECKING:  # torch is imported by the code that runs a loss (the engine), not by editors
    import torch

    from engine.kinematics.pose_state import PoseState


@dataclass
class PinConstraint(Constraint):
    """Keep ``joint`` at ``position`` (metres), see the module doc."""

    kind: ClassVar[str] = "pin"
    weight: float = 30.0
    joint: str = param("lankle", editor="joint")
    position: np.ndarray = param(factory=lambda: np.full(3, np.nan), editor="vec3", unit="m")
    follow_previous: bool = param(False, editor="bool")
    tolerance: float = param(0.01, editor="float", unit="m")

    def check(self) -> None:
        joint_index(self.joint, "joint", self.kind)

    def acts_on(self) -> tuple[str, ...]:
        return (self.joint,)

    def _target(self, previous: Any) -> Any:
        """The target (same type as ``previous``'s rows), or None while there is none."""
        j = joint_index(self.joint, "joint", self.kind)
        if self.follow_previous and previous is not None:
            return previous[j]
        if np.all(np.isfinite(self.position)):
            return self.position
        return None if previous is None else previous[j]

    def loss(self, state: PoseState) -> torch.Tensor:
        import torch
        j = joint_index(self.joint, "joint", self.kind)
        prev = None if state.previous_positions is None else state.previous_positions.detach()
        target = self._target(prev)
        if target is None:
            return state.positions.new_zeros(())
        t = target if isinstance(target, torch.Tensor) else vec(target, state.positions)
        return ((state.positions[j] - t) ** 2).sum()

    def satisfied(self, state: PoseState) -> bool:
        import torch
        with torch.no_grad():
            return float(self.loss(state)) <= self.tolerance**2

    def settled(self, previous_positions: np.ndarray | None) -> "PinConstraint":
        """A copy holding the previous pose's joint position when ``position`` is unset."""
        if self.follow_previous or previous_positions is None or np.all(np.isfinite(self.position)):
            return self
        j = joint_index(self.joint, "joint", self.kind)
        return dataclasses.replace(self, position=np.array(previous_positions[j], dtype=np.float64))

    def fast_term(self, frame: FrameInputs) -> "PinTerm":
        return PinTerm(self, self._target(frame.previous_positions))

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


class PinTerm:
    """The fast-path term of one :class:`PinConstraint` for one frame (module doc)."""

    def __init__(self, c: PinConstraint, target: np.ndarray | None) -> None:
        self.name, self.weight, self.turns, self.tol2 = c.name, c.weight, False, c.tolerance**2
        self.j = joint_index(c.joint, "joint", c.kind)
        self.target = None if target is None else np.asarray(target, dtype=np.float64)

    def evaluate(self, pos: np.ndarray, world: np.ndarray, g_pos: np.ndarray, g_rot: np.ndarray) -> float:
        if self.target is None:
            return 0.0
        d = pos[self.j] - self.target
        g_pos[self.j] += (2.0 * self.weight) * d
        return float(d @ d)

    def satisfied(self, pos: np.ndarray, world: np.ndarray) -> bool:
        if self.target is None:
            return True
        d = pos[self.j] - self.target
        return float(d @ d) <= self.tol2
