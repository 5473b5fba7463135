"""``bounds``: a joint stays inside an axis-aligned box.

Loss: ``sum(relu(box_min - p)^2 + relu(p - box_max)^2)`` over x, y, z (metres squared),
the squared norm of the residual ``relu(p - box_max) - relu(box_min - p)`` (one entry per
axis, its Jacobian 1 on an axis outside the box).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, ClassVar

import numpy as np

from engine.constraints.base import Constraint, OnOneJoint, joint_index, param
from engine.constraints.placement import BOUNDS_HALF, joint_at
from engine.constraints.residual import FrameInputs, Kit, Residuals, Term
from engine.errors import UserError
from engine.gizmos import BoxGizmo

_SLACK = 1e-3  # metres: satisfied this far outside the box


@dataclass
class BoundsConstraint(OnOneJoint, Constraint):
    """Keep ``joint`` within ``[box_min, box_max]`` (world, metres)."""

    kind: ClassVar[str] = "bounds"
    joint: str = param("root", editor="joint")
    box_min: np.ndarray = param(factory=lambda: np.array([-1.0, -1.0, 0.0]), editor="vec3", unit="m")
    box_max: np.ndarray = param(factory=lambda: np.array([1.0, 1.0, 2.0]), editor="vec3", unit="m")

    def check(self) -> None:
        super().check()
        if np.any(self.box_min > self.box_max):
            raise UserError(f"constraint {self.kind!r}: field 'box_min' exceeds 'box_max' on some axis")

    def term(self, frame: FrameInputs) -> "BoundsTerm":
        return BoundsTerm(self)

    @classmethod
    def examples(cls, positions: np.ndarray) -> list[Constraint]:
        w = positions[joint_index("lwrist")]
        return [
            cls(joint="lwrist", box_min=w + [0.05, -0.5, -0.5], box_max=w + [0.5, -0.02, 0.5]),
            cls(weight=2.0, box_min=np.array([-5.0, -5.0, 1.5]), box_max=np.array([5.0, 5.0, 3.0])),
        ]

    @classmethod
    def placement(cls, params: dict[str, Any], positions: np.ndarray) -> dict[str, Any]:
        """A box of half size :data:`BOUNDS_HALF` around the joint."""
        c = joint_at(positions, params.get("joint"), "root")
        return {"box_min": c - BOUNDS_HALF, "box_max": c + BOUNDS_HALF}

    def gizmo(self, positions: np.ndarray | None = None) -> BoxGizmo:
        return BoxGizmo(self.box_min, self.box_max, edit=("box_min", "box_max"))


class BoundsTerm(Term):
    """``relu(p - box_max) - relu(box_min - p)`` per axis (module doc)."""

    def __init__(self, c: BoundsConstraint) -> None:
        self.names, self.owner = (c.name,), np.zeros(3, dtype=np.intp)
        self.check_group, self.check_limit2 = np.arange(3), np.full(3, _SLACK**2)  # each axis alone
        self.j = np.array([joint_index(c.joint, "joint", c.kind)], dtype=np.intp)
        self.lo, self.hi = np.asarray(c.box_min, dtype=np.float64), np.asarray(c.box_max, dtype=np.float64)

    def residual(self, kit: Kit, P: Any, W: Any, z: Any, jac: bool = False, rows: Any = None) -> Residuals:
        p = P[:, self.j[0]]
        r = kit.relu(p - kit.const(self.hi, P)) - kit.relu(kit.const(self.lo, P) - p)
        if not jac:
            return Residuals(r)
        d = np.zeros((len(P), 3, 1, 3))
        d[:, np.arange(3), 0, np.arange(3)] = (r != 0.0).astype(float)
        return Residuals(r, self.j, d)
