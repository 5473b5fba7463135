"""``bounds``: a joint stays inside an axis-aligned box.

Loss: ``sum(relu(box_min - p)^2 + relu(p - box_max)^2)`` over x, y, z (metres squared);
its gradient (fast path) is ``2 (p - box_max)`` above the box and ``2 (p - box_min)``
below it, per axis.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, ClassVar, TYPE_CHECKING

import numpy as np

from engine.constraints.base import Constraint, joint_index, param, vec
from engine.constraints.placement import BOUNDS_HALF, joint_at
from engine.constraints.terms import FrameInputs
from engine.errors import UserError
from engine.gizmos import BoxGizmo

if TYPE_CHECKING:  # torch is imported by the code that runs a loss (the engine), not by editors
    import torch

    from engine.kinematics.pose_state import PoseState

_SLACK = 1e-3  # metres: satisfied this far outside the box


@dataclass
class BoundsConstraint(Constraint):
    """Keep ``joint`` within ``[box_min, box_max]`` (world, metres)."""

    kind: ClassVar[str] = "bounds"
    joint: str = param("root", editor="joint")
    box_min: np.ndarray = param(factory=lambda: np.array([-1.0, -1.0, 0.0]), editor="vec3", unit="m")
    box_max: np.ndarray = param(factory=lambda: np.array([1.0, 1.0, 2.0]), editor="vec3", unit="m")

    def check(self) -> None:
        joint_index(self.joint, "joint", self.kind)
        if np.any(self.box_min > self.box_max):
            raise UserError(f"constraint {self.kind!r}: field 'box_min' exceeds 'box_max' on some axis")

    def acts_on(self) -> tuple[str, ...]:
        return (self.joint,)

    def loss(self, state: PoseState) -> torch.Tensor:
        import torch
        p = state.positions[joint_index(self.joint, "joint", self.kind)]
        lo, hi = vec(self.box_min, p), vec(self.box_max, p)
        return (torch.relu(lo - p) ** 2 + torch.relu(p - hi) ** 2).sum()

    def satisfied(self, state: PoseState) -> bool:
        p = state.positions[joint_index(self.joint, "joint", self.kind)].detach().cpu().numpy()
        return bool(np.all(p >= self.box_min - _SLACK) and np.all(p <= self.box_max + _SLACK))

    def fast_term(self, frame: FrameInputs) -> "BoundsTerm":
        return BoundsTerm(self)

    @classmethod
    def placement(cls, params: dict[str, Any], positions: np.ndarray) -> dict[str, Any]:
        """A box of half size :data:`BOUNDS_HALF` around the joint."""
        c = joint_at(positions, params.get("joint"), "root")
        return {"box_min": c - BOUNDS_HALF, "box_max": c + BOUNDS_HALF}

    def gizmo(self, positions: np.ndarray | None = None) -> BoxGizmo:
        return BoxGizmo(self.box_min, self.box_max, edit=("box_min", "box_max"))


class BoundsTerm:
    """The fast-path term of one :class:`BoundsConstraint` (module doc)."""

    def __init__(self, c: BoundsConstraint) -> None:
        self.name, self.weight, self.turns = c.name, c.weight, False
        self.j = joint_index(c.joint, "joint", c.kind)
        self.lo, self.hi = np.asarray(c.box_min, dtype=np.float64), np.asarray(c.box_max, dtype=np.float64)

    def _excess(self, pos: np.ndarray) -> np.ndarray:
        p = pos[self.j]
        return np.maximum(p - self.hi, 0.0) - np.maximum(self.lo - p, 0.0)

    def evaluate(self, pos: np.ndarray, world: np.ndarray, g_pos: np.ndarray, g_rot: np.ndarray) -> float:
        e = self._excess(pos)
        g_pos[self.j] += (2.0 * self.weight) * e
        return float(e @ e)

    def satisfied(self, pos: np.ndarray, world: np.ndarray) -> bool:
        p = pos[self.j]
        return bool(np.all(p >= self.lo - _SLACK) and np.all(p <= self.hi + _SLACK))
