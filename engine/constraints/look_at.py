"""``look_at``: the head's forward axis points at a world point (DragPoser sec. 5.2).

The forward axis is given in the joint's own frame. In the canonical rest pose every
joint's world rotation is the identity and the character faces -Y, so the head's
(``upperneck``) forward axis is ``(0, -1, 0)``.

Residual: with ``f = W_j axis`` and ``u = t / |t|`` the unit direction to the target
(``t = target - P_j``), ``(f - u) / sqrt(2)``, whose squared norm ``(2 - 2 f.u) / 2`` is the
loss ``1 - cos``. Its Jacobian is ``(I - u u^T) / (|t| sqrt(2))`` on ``P_j`` and ``-[f]x /
sqrt(2)`` on the joint's turn (turning it by ``a`` moves ``f`` by ``a x f``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, ClassVar

import numpy as np

from engine.constraints.base import Constraint, OnOneJoint, joint_index, param
from engine.constraints.placement import LOOK_DISTANCE, facing, joint_at
from engine.constraints.residual import FrameInputs, Kit, Residuals, Term
from engine.constraints.rotation_residual import EPS3
from engine.errors import UserError
from engine.gizmos import LineGizmo, PointGizmo

_MIN_DISTANCE = 1e-6  # metres: the direction to a target this close is not defined
_HALF = math.sqrt(0.5)
_EYE = np.eye(3)
#: ``f @ _TURN`` is ``d r_i / d a_k = -[f]x_ik / sqrt(2) = EPS3[i, k, l] f_l / sqrt(2)`` as ``(3 i + k)``.
_TURN = np.ascontiguousarray(EPS3.transpose(2, 0, 1).reshape(3, 9)) * _HALF


@dataclass
class LookAtConstraint(OnOneJoint, Constraint):
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
    joint: str = param("upperneck", editor="joint")
    target: np.ndarray = param(factory=lambda: np.array([0.0, -2.0, 1.6]), editor="vec3", unit="m")
    axis: np.ndarray = param(factory=lambda: np.array([0.0, -1.0, 0.0]), editor="vec3")
    tolerance: float = param(5.0, editor="float", unit="deg")

    def check(self) -> None:
        super().check()
        if not np.linalg.norm(self.axis) > 1e-9:
            raise UserError(f"constraint {self.kind!r}: field 'axis' must be a non-zero vector")

    def term(self, frame: FrameInputs) -> "LookAtTerm":
        return LookAtTerm(self)

    @classmethod
    def examples(cls, positions: np.ndarray) -> list[Constraint]:
        head, wrist = positions[joint_index("upperneck")], positions[joint_index("lwrist")]
        return [
            cls(weight=2.0, target=head + [0.9, -0.4, 0.3]),
            cls(joint="lwrist", axis=np.array([1.0, 0.2, 0.0]), target=wrist + [0.0, -0.5, 0.1]),
        ]

    @classmethod
    def placement(cls, params: dict[str, Any], positions: np.ndarray) -> dict[str, Any]:
        """The target in front of the looking joint, at :data:`LOOK_DISTANCE`."""
        return {"target": joint_at(positions, params.get("joint"), "upperneck") + LOOK_DISTANCE * facing(positions)}

    def gizmo(self, positions: np.ndarray | None = None) -> PointGizmo | LineGizmo:
        target = np.asarray(self.target, float)
        if positions is None:
            return PointGizmo(target, edit="target")
        start = np.asarray(positions, float)[joint_index(self.joint, "joint", self.kind)]
        # the line's end (the target) stays draggable once a pose exists
        return LineGizmo(np.stack([start, target]), edit="target")


class LookAtTerm(Term):
    """``(f - t / |t|) / sqrt(2)`` for the forward axis ``f = W_j axis`` and ``t = target -
    P_j``: its squared norm is ``1 - cos`` of the angle between them (module doc)."""

    def __init__(self, c: LookAtConstraint) -> None:
        self.names, self.owner = (c.name,), np.zeros(3, dtype=np.intp)
        self.j = np.array([joint_index(c.joint, "joint", c.kind)], dtype=np.intp)
        self.entries = np.repeat(self.j, 3)  # each entry reads the joint: per-entry blocks
        self.axis = np.asarray(c.axis, dtype=np.float64) / np.linalg.norm(c.axis)
        self.target = np.asarray(c.target, dtype=np.float64)
        # |r|^2 = 1 - cos(angle) (unit f and u), so the angle is within the tolerance when
        # |r|^2 <= 1 - cos(tolerance)
        self.check_group = np.zeros(3, dtype=np.intp)
        self.check_limit2 = np.array([1.0 - math.cos(math.radians(c.tolerance))])

    def residual(self, kit: Kit, P: Any, W: Any, z: Any, jac: bool = False, rows: Any = None) -> Residuals:
        f = W[:, self.j[0]] @ kit.const(self.axis, P)  # (A, 3)
        t = kit.const(self.target, P) - P[:, self.j[0]]
        n = kit.clamp_min(kit.sqrt((t * t).sum(-1)), _MIN_DISTANCE)
        u = t / n[:, None]
        r = (f - u) * _HALF
        if not jac:
            return Residuals(r)
        u_free = u * (n > _MIN_DISTANCE)[:, None]  # below it |t| is a constant
        d_pos = (_EYE - u[:, :, None] * u_free[:, None, :]) / n[:, None, None] * _HALF
        d_rot = (f @ _TURN).reshape(-1, 3, 3)  # turning by a moves f by a x f
        return Residuals(r, entry_joint=self.entries, d_pos_entry=d_pos, d_rot_entry=d_rot)
