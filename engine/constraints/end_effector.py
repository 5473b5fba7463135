"""``end_effector``: a joint reaches a fixed world target (position, optionally rotation).

Fast path: the position term ``|P_j - t|^2`` has gradient ``2 (P_j - t)``; the rotation
term is the sensors' ``sin^2(angle / 2)`` (:func:`engine.constraints.terms.rotation_term`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, ClassVar, TYPE_CHECKING

import numpy as np

from engine.constraints.base import Constraint, joint_index, param, rotation_distance, vec
from engine.constraints.placement import REACH, facing, joint_at
from engine.constraints.terms import FrameInputs, rotation_term, unit_quaternion_matrix
from engine.gizmos import PointGizmo

if TYPE_CHECKING:  # torch is imported by the code that runs a loss (the engine), not by editors
    import torch

    from engine.kinematics.pose_state import PoseState


@dataclass
class EndEffectorConstraint(Constraint):
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

    def check(self) -> None:
        joint_index(self.joint, "joint", self.kind)

    def acts_on(self) -> tuple[str, ...]:
        return (self.joint,)

    def loss(self, state: PoseState) -> torch.Tensor:
        j = joint_index(self.joint, "joint", self.kind)
        out = ((state.positions[j] - vec(self.position, state.positions)) ** 2).sum()
        if self.use_rotation:
            out = out + self.rotation_weight * rotation_distance(state, j, self.rotation)
        return out

    def satisfied(self, state: PoseState) -> bool:
        j = joint_index(self.joint, "joint", self.kind)
        err = np.linalg.norm(state.positions[j].detach().cpu().numpy() - self.position)
        return bool(err <= self.tolerance) or not math.isfinite(err)

    def fast_term(self, frame: FrameInputs) -> "EndEffectorTerm":
        return EndEffectorTerm(self)

    @classmethod
    def placement(cls, params: dict[str, Any], positions: np.ndarray) -> dict[str, Any]:
        """The target :data:`REACH` in front of the joint."""
        return {"position": joint_at(positions, params.get("joint"), "lwrist") + REACH * facing(positions)}

    def gizmo(self, positions: np.ndarray | None = None) -> PointGizmo:
        return PointGizmo(self.position, edit="position")


class EndEffectorTerm:
    """The fast-path term of one :class:`EndEffectorConstraint` (module doc)."""

    def __init__(self, c: EndEffectorConstraint) -> None:
        self.name, self.weight, self.turns, self.tolerance = c.name, c.weight, c.use_rotation, c.tolerance
        self.j = joint_index(c.joint, "joint", c.kind)
        self.target = np.asarray(c.position, dtype=np.float64)
        self.rot = unit_quaternion_matrix(c.rotation) if c.use_rotation else None
        self.rot_weight = c.rotation_weight

    def evaluate(self, pos: np.ndarray, world: np.ndarray, g_pos: np.ndarray, g_rot: np.ndarray) -> float:
        d = pos[self.j] - self.target
        g_pos[self.j] += (2.0 * self.weight) * d
        out = float(d @ d)
        if self.rot is not None:
            _, value, grad = rotation_term(self.rot, world[self.j])
            g_rot[self.j] += (self.weight * self.rot_weight) * grad
            out += self.rot_weight * value
        return out

    def satisfied(self, pos: np.ndarray, world: np.ndarray) -> bool:
        err = float(np.linalg.norm(pos[self.j] - self.target))
        return err <= self.tolerance or not math.isfinite(err)
