"""``pin``: a joint stays where it was.

Its default weight is 30, not 1: a pin is the user overriding the trackers, and at
weight 1 six sensor terms of the same scale (squared metres) held a Ctrl-dragged elbow
10-13 cm short of the pin with the shipped DragPoser; at 30 it pulls the joint in over
a few frames and holds it within ~2 cm; ``scripts/measure_pin.py`` measures it
(docs/studio.md, "Pins").

With ``follow_previous`` the target is the joint's previous-frame position every frame
(the joint resists motion). Otherwise the target is ``position``; while that is unset
(NaN) it is captured from the previous frame's solved pose on first use (or, on the very
first frame, from the pose being solved, which costs nothing that frame).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, ClassVar

import numpy as np
import torch

from engine.constraints.base import Constraint, joint_index, vec
from engine.solver.state import PoseState


@dataclass
class PinConstraint(Constraint):
    """Keep ``joint`` at ``position`` (metres), see the module doc."""

    kind: ClassVar[str] = "pin"
    weight: float = 30.0
    joint: str = "lankle"
    position: np.ndarray = field(default_factory=lambda: np.full(3, np.nan))
    follow_previous: bool = False
    tolerance: float = 0.01

    def check(self) -> None:
        joint_index(self.joint, "joint", self.kind)

    def _target(self, state: PoseState) -> torch.Tensor:
        j = joint_index(self.joint, "joint", self.kind)
        if self.follow_previous and state.previous_positions is not None:
            return state.previous_positions[j].detach()
        if not np.all(np.isfinite(self.position)):
            src = state.previous_positions if state.previous_positions is not None else state.positions
            self.position = src[j].detach().cpu().numpy().astype(np.float64)
        return vec(self.position, state.positions)

    def loss(self, state: PoseState) -> torch.Tensor:
        j = joint_index(self.joint, "joint", self.kind)
        return ((state.positions[j] - self._target(state)) ** 2).sum()

    def satisfied(self, state: PoseState) -> bool:
        with torch.no_grad():
            return float(self.loss(state)) <= self.tolerance**2

    def gizmo(self, positions: np.ndarray | None = None) -> dict[str, Any]:
        """A draggable point labelled with the joint, tied to the joint by a line."""
        if not np.all(np.isfinite(self.position)):
            return {}
        g = {"type": "point", "position": self.position.copy(), "edit": "position", "label": self.joint}
        if positions is not None:
            g["anchor"] = np.asarray(positions, float)[joint_index(self.joint, "joint", self.kind)].copy()
        return g
