"""``end_effector``: a joint reaches a fixed world target (position, optionally rotation).

Residual: ``P_j - t`` and, with a rotation, the trackers' rotation residual, whose squared
norm is ``rotation_weight * sin^2(angle / 2)``
(:func:`engine.constraints.rotation_residual.rotation_residual`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, ClassVar

import numpy as np

from engine.constraints.base import Constraint, OnOneJoint, joint_index, param
from engine.constraints.placement import REACH, facing, joint_at
from engine.constraints.residual import FrameInputs, Kit, Residuals, Term
from engine.constraints.rotation_residual import entry_block, rotation_residual
from engine.gizmos import PointGizmo
from engine.kinematics import quat_np as QN


@dataclass
class EndEffectorConstraint(OnOneJoint, Constraint):
    """Pull ``joint`` to ``position`` (and to ``rotation`` if ``use_rotation``).

    Parameters
    ----------
    joint : str
        Canonical joint, e.g. ``lwrist``.
    position : ndarray (3,)
        World target, metres.
    rotation : ndarray (4,)
        World target rotation (w, x, y, z), used when ``use_rotation`` is set.
    use_rotation : bool
        Add the sign-invariant rotation term ``rotation_weight * (1 - <q, q_t>^2)``.
    rotation_weight : float
        Weight of the rotation term.
    tolerance : float
        Metres; satisfied when the position error is below it.
    """

    kind: ClassVar[str] = "end_effector"
    joint: str = param("lwrist", editor="joint")
    position: np.ndarray = param(factory=lambda: np.array([0.3, -0.3, 1.2]), editor="vec3", unit="m")
    rotation: np.ndarray = param(factory=lambda: np.array([1.0, 0.0, 0.0, 0.0]), editor="quat")
    use_rotation: bool = param(False, editor="bool")
    rotation_weight: float = param(0.1, editor="float")
    tolerance: float = param(0.01, editor="float", unit="m")

    def term(self, frame: FrameInputs) -> "EndEffectorTerm":
        return EndEffectorTerm(self)

    @classmethod
    def examples(cls, positions: np.ndarray) -> list[Constraint]:
        ankle, wrist = positions[joint_index("rankle")], positions[joint_index("lwrist")]
        turn = np.array([math.cos(0.55), 0.3 * math.sin(0.55), 0.95 * math.sin(0.55), 0.0])
        return [
            cls(joint="rankle", position=ankle + [0.1, 0.0, 0.1]),
            cls(
                joint="lwrist",
                position=wrist + [0.0, 0.01, 0.0],
                use_rotation=True,
                rotation_weight=0.7,
                rotation=turn / np.linalg.norm(turn),
            ),
        ]

    @classmethod
    def placement(cls, params: dict[str, Any], positions: np.ndarray) -> dict[str, Any]:
        """The target :data:`REACH` in front of the joint."""
        return {"position": joint_at(positions, params.get("joint"), "lwrist") + REACH * facing(positions)}

    def gizmo(self, positions: np.ndarray | None = None) -> PointGizmo:
        return PointGizmo(self.position, edit="position")


class EndEffectorTerm(Term):
    """``P_j - t`` and, with a rotation, ``sqrt(rotation_weight / 8) (W_j - T)`` (module doc)."""

    def __init__(self, c: EndEffectorConstraint) -> None:
        self.names = (c.name,)
        self.j = np.array([joint_index(c.joint, "joint", c.kind)], dtype=np.intp)
        self.target = np.asarray(c.position, dtype=np.float64)
        self.rot = QN.unit_to_matrix(c.rotation)[None, None] if c.use_rotation else None
        self.scale = np.full((1, 1), math.sqrt(c.rotation_weight / 8.0))
        self.owner = np.zeros(12 if c.use_rotation else 3, dtype=np.intp)
        self.check_group = np.r_[np.zeros(3, dtype=np.intp), np.full(len(self.owner) - 3, -1)]  # the position only
        self.check_limit2 = np.array([c.tolerance**2])

    def residual(self, kit: Kit, P: Any, W: Any, z: Any, jac: bool = False, rows: Any = None) -> Residuals:
        a = P.shape[0]
        r = P[:, self.j[0]] - kit.const(self.target, P)
        every, m = slice(0, a), len(self.owner)  # the term's parameters are the same for every frame
        d_rot = rot_rows = None
        if self.rot is not None:
            scale = np.broadcast_to(self.scale, (a, 1))
            if jac:  # a block whose position rows stay zero; its rotation rows are written in place
                d_rot, rot_rows = self.kept("d_rot", every, lambda: entry_block((a, m, 3), 3))
            rot, _ = rotation_residual(kit, W[:, self.j], kit.const(self.rot, P), kit.const(scale, P), jac, rot_rows)
            r = kit.cat([r, rot], -1)
        if not jac:
            return Residuals(r)
        joints = self.kept("joints", every, lambda: np.repeat(self.j, m))
        d_pos = self.kept("d_pos", every, lambda: _position_jacobian(a, m))
        return Residuals(r, entry_joint=joints, d_pos_entry=d_pos, d_rot_entry=d_rot)


def _position_jacobian(a: int, m: int) -> np.ndarray:
    """``(A, m, 3)``: the identity for the 3 position entries, zero for the rotation ones."""
    d_pos = np.zeros((a, m, 3))
    d_pos[:, :3] = np.eye(3)
    return d_pos
