"""``look_at``: the head's forward axis points at a world point (DragPoser sec. 5.2).

The forward axis is given in the joint's own frame. In the canonical rest pose every
joint's world rotation is the identity and the character faces -Y, so the head's
(``upperneck``) forward axis is ``(0, -1, 0)``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any, ClassVar

import numpy as np
import torch

from engine.constraints.base import Constraint, joint_index, vec, world_rotation_matrix
from engine.errors import UserError
from engine.solver.state import PoseState


@dataclass
class LookAtConstraint(Constraint):
    """``1 - cos(angle)`` between the joint's forward axis and the direction to ``target``.

    Parameters
    ----------
    joint : str
        The looking joint (default ``upperneck``, the head).
    target : ndarray (3,)
        World point to look at, metres.
    axis : ndarray (3,)
        Forward axis in the joint's frame (rest pose: -Y).
    tolerance : float
        Degrees; satisfied when the angle is below it.
    """

    kind: ClassVar[str] = "look_at"
    joint: str = "upperneck"
    target: np.ndarray = field(default_factory=lambda: np.array([0.0, -2.0, 1.6]))
    axis: np.ndarray = field(default_factory=lambda: np.array([0.0, -1.0, 0.0]))
    tolerance: float = 5.0

    def check(self) -> None:
        joint_index(self.joint, "joint", self.kind)
        if not np.linalg.norm(self.axis) > 1e-9:
            raise UserError(f"constraint {self.kind!r}: field 'axis' must be a non-zero vector")

    def _cos(self, state: PoseState) -> torch.Tensor:
        j = joint_index(self.joint, "joint", self.kind)
        axis = vec(self.axis / np.linalg.norm(self.axis), state.positions)
        forward = world_rotation_matrix(state, j) @ axis
        to_target = vec(self.target, state.positions) - state.positions[j]
        return (forward * to_target).sum() / to_target.norm().clamp_min(1e-6)

    def loss(self, state: PoseState) -> torch.Tensor:
        return 1.0 - self._cos(state)

    def satisfied(self, state: PoseState) -> bool:
        with torch.no_grad():
            c = float(self._cos(state))
        return c >= math.cos(math.radians(self.tolerance)) or not math.isfinite(c)

    def gizmo(self, positions: np.ndarray | None = None) -> dict[str, Any]:
        target = np.asarray(self.target, float).copy()
        if positions is None:
            return {"type": "point", "position": target, "edit": "target"}
        start = np.asarray(positions, float)[joint_index(self.joint, "joint", self.kind)]
        # the line's end (the target) stays draggable once a pose exists
        return {"type": "line", "points": np.stack([start, target]), "edit": "target"}
