"""``distance``: two joints at a given distance, loss ``(|p_a - p_b| - d)^2`` (m^2).

Residual ``|p_a - p_b| - d``; its Jacobian is the unit vector ``(p_a - p_b) / |p_a - p_b|``
at ``p_a`` and its negative at ``p_b``.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, ClassVar

import numpy as np

from engine.constraints.base import Constraint, joint_index, param
from engine.constraints.placement import joint_at
from engine.constraints.residual import FrameInputs, Kit, Residuals, Term
from engine.errors import UserError
from engine.gizmos import LineGizmo

_SIGNS = np.array([[1.0], [-1.0]])  # the unit vector at joint a, its negative at joint b
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

    def term(self, frame: FrameInputs) -> "DistanceTerm":
        return DistanceTerm(self)

    @classmethod
    def examples(cls, positions: np.ndarray) -> list[Constraint]:
        return [cls(weight=5.0, distance=0.9), cls(joint_a="lankle", joint_b="upperneck", distance=0.2)]

    @classmethod
    def placement(cls, params: dict[str, Any], positions: np.ndarray) -> dict[str, Any]:
        """The joints' distance as they stand (the new constraint starts satisfied)."""
        a, b = (
            joint_at(positions, params.get("joint_a"), "lwrist"),
            joint_at(positions, params.get("joint_b"), "rwrist"),
        )
        return {"distance": float(np.linalg.norm(a - b))}

    def gizmo(self, positions: np.ndarray | None = None) -> LineGizmo | None:
        if positions is None:
            return None
        p = np.asarray(positions, float)
        a, b = self._pair()
        return LineGizmo(np.stack([p[a], p[b]]))


class DistanceTerm(Term):
    """``|p_a - p_b| - distance`` (module doc)."""

    def __init__(self, c: DistanceConstraint) -> None:
        self.names, self.owner = (c.name,), np.zeros(1, dtype=np.intp)
        self.distance = c.distance
        self.check_group, self.check_limit2 = np.zeros(1, dtype=np.intp), np.array([c.tolerance**2])
        self.joints = np.array(c._pair(), dtype=np.intp)

    def residual(self, kit: Kit, P: Any, W: Any, z: Any, jac: bool = False, rows: Any = None) -> Residuals:
        d = P[:, self.joints[0]] - P[:, self.joints[1]]
        squared = (d * d).sum(-1)
        length = kit.sqrt(kit.clamp_min(squared, _MIN_SQUARED))
        r = (length - self.distance)[:, None]
        if not jac:
            return Residuals(r)
        u = d / length[:, None] * (squared > _MIN_SQUARED)[:, None]  # within the clamp: constant
        return Residuals(r, self.joints, u[:, None, None, :] * _SIGNS)
