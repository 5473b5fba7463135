"""``bounds``: a joint stays inside an axis-aligned box.

Loss: ``sum(relu(box_min - p)^2 + relu(p - box_max)^2)`` over x, y, z (metres squared).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, ClassVar

import numpy as np
import torch

from engine.constraints.base import Constraint, joint_index, vec
from engine.errors import UserError
from engine.solver.state import PoseState


@dataclass
class BoundsConstraint(Constraint):
    """Keep ``joint`` within ``[box_min, box_max]`` (world, metres)."""

    kind: ClassVar[str] = "bounds"
    joint: str = "root"
    box_min: np.ndarray = field(default_factory=lambda: np.array([-1.0, -1.0, 0.0]))
    box_max: np.ndarray = field(default_factory=lambda: np.array([1.0, 1.0, 2.0]))

    def check(self) -> None:
        joint_index(self.joint, "joint", self.kind)
        if np.any(self.box_min > self.box_max):
            raise UserError(f"constraint {self.kind!r}: field 'box_min' exceeds 'box_max' on some axis")

    def loss(self, state: PoseState) -> torch.Tensor:
        p = state.positions[joint_index(self.joint, "joint", self.kind)]
        lo, hi = vec(self.box_min, p), vec(self.box_max, p)
        return (torch.relu(lo - p) ** 2 + torch.relu(p - hi) ** 2).sum()

    def satisfied(self, state: PoseState) -> bool:
        p = state.positions[joint_index(self.joint, "joint", self.kind)].detach().cpu().numpy()
        return bool(np.all(p >= self.box_min - 1e-3) and np.all(p <= self.box_max + 1e-3))

    def gizmo(self, positions: np.ndarray | None = None) -> dict[str, Any]:
        return {"type": "box", "min": self.box_min.copy(), "max": self.box_max.copy(),
                "edit": ("box_min", "box_max")}  # fmt: skip
