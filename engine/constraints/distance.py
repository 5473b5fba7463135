"""``distance``: two joints at a given distance, loss ``(|p_a - p_b| - d)^2`` (m^2)."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, ClassVar

import numpy as np
import torch

from engine.constraints.base import Constraint, joint_index
from engine.errors import UserError
from engine.solver.state import PoseState


@dataclass
class DistanceConstraint(Constraint):
    """Keep ``joint_a`` and ``joint_b`` ``distance`` metres apart.

    Parameters
    ----------
    joint_a, joint_b : str
        Canonical joints.
    distance : float
        Metres (>= 0).
    tolerance : float
        Metres; satisfied within it.
    """

    kind: ClassVar[str] = "distance"
    joint_a: str = "lwrist"
    joint_b: str = "rwrist"
    distance: float = 0.3
    tolerance: float = 0.01

    def check(self) -> None:
        joint_index(self.joint_a, "joint_a", self.kind)
        joint_index(self.joint_b, "joint_b", self.kind)
        if self.distance < 0:
            raise UserError(f"constraint {self.kind!r}: field 'distance' must be >= 0")

    def _length(self, positions: torch.Tensor) -> torch.Tensor:
        a = joint_index(self.joint_a, "joint_a", self.kind)
        b = joint_index(self.joint_b, "joint_b", self.kind)
        # clamped so the gradient stays finite when the joints coincide
        return ((positions[a] - positions[b]) ** 2).sum().clamp_min(1e-12).sqrt()

    def loss(self, state: PoseState) -> torch.Tensor:
        return (self._length(state.positions) - self.distance) ** 2

    def satisfied(self, state: PoseState) -> bool:
        return abs(float(self._length(state.positions.detach())) - self.distance) <= self.tolerance

    def gizmo(self, positions: np.ndarray | None = None) -> dict[str, Any]:
        if positions is None:
            return {}
        p = np.asarray(positions, float)
        a = joint_index(self.joint_a, "joint_a", self.kind)
        b = joint_index(self.joint_b, "joint_b", self.kind)
        return {"type": "line", "points": np.stack([p[a], p[b]])}
