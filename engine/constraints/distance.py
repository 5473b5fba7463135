"""``distance``: two joints at a given distance, loss ``(|p_a - p_b| - d)^2`` (m^2).

Fast path: with ``l = |p_a - p_b|``, the gradient at ``p_a`` is ``2 (l - d) (p_a - p_b) / l``
and its negative at ``p_b``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, ClassVar, TYPE_CHECKING

import numpy as np

from engine.constraints.base import Constraint, joint_index, param
from engine.constraints.placement import joint_at
from engine.constraints.terms import FrameInputs
from engine.errors import UserError
from engine.gizmos import LineGizmo

if TYPE_CHECKING:  # torch is imported by the code that runs a loss (the engine), not by editors
    import torch

    from engine.kinematics.pose_state import PoseState

_MIN_SQUARED = 1e-12  # m^2: the length is clamped so its gradient stays finite when the joints coincide


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
    joint_a: str = param("lwrist", editor="joint")
    joint_b: str = param("rwrist", editor="joint")
    distance: float = param(0.3, editor="float", unit="m")
    tolerance: float = param(0.01, editor="float", unit="m")

    def check(self) -> None:
        joint_index(self.joint_a, "joint_a", self.kind)
        joint_index(self.joint_b, "joint_b", self.kind)
        if self.distance < 0:
            raise UserError(f"constraint {self.kind!r}: field 'distance' must be >= 0")

    def acts_on(self) -> tuple[str, ...]:
        return (self.joint_a, self.joint_b)

    def _pair(self) -> tuple[int, int]:
        return joint_index(self.joint_a, "joint_a", self.kind), joint_index(self.joint_b, "joint_b", self.kind)

    def _length(self, positions: torch.Tensor) -> torch.Tensor:
        a, b = self._pair()
        return ((positions[a] - positions[b]) ** 2).sum().clamp_min(_MIN_SQUARED).sqrt()

    def loss(self, state: PoseState) -> torch.Tensor:
        return (self._length(state.positions) - self.distance) ** 2

    def satisfied(self, state: PoseState) -> bool:
        return abs(float(self._length(state.positions.detach())) - self.distance) <= self.tolerance

    def fast_term(self, frame: FrameInputs) -> "DistanceTerm":
        return DistanceTerm(self)

    @classmethod
    def placement(cls, params: dict[str, Any], positions: np.ndarray) -> dict[str, Any]:
        """The joints' distance as they stand (the new constraint starts satisfied)."""
        a, b = joint_at(positions, params.get("joint_a"), "lwrist"), joint_at(positions, params.get("joint_b"), "rwrist")
        return {"distance": float(np.linalg.norm(a - b))}

    def gizmo(self, positions: np.ndarray | None = None) -> LineGizmo | None:
        if positions is None:
            return None
        p = np.asarray(positions, float)
        a, b = self._pair()
        return LineGizmo(np.stack([p[a], p[b]]))


class DistanceTerm:
    """The fast-path term of one :class:`DistanceConstraint` (module doc)."""

    def __init__(self, c: DistanceConstraint) -> None:
        self.name, self.weight, self.turns = c.name, c.weight, False
        self.distance, self.tolerance = c.distance, c.tolerance
        self.a, self.b = c._pair()

    def _length(self, pos: np.ndarray) -> tuple[np.ndarray, float, bool]:
        d = pos[self.a] - pos[self.b]
        s = float(d @ d)
        return d, math.sqrt(max(s, _MIN_SQUARED)), s > _MIN_SQUARED

    def evaluate(self, pos: np.ndarray, world: np.ndarray, g_pos: np.ndarray, g_rot: np.ndarray) -> float:
        d, length, free = self._length(pos)
        if free:  # within the clamp the length is constant
            g = (2.0 * self.weight * (length - self.distance) / length) * d
            g_pos[self.a] += g
            g_pos[self.b] -= g
        return (length - self.distance) ** 2

    def satisfied(self, pos: np.ndarray, world: np.ndarray) -> bool:
        return abs(self._length(pos)[1] - self.distance) <= self.tolerance
