"""``end_effector``: a joint reaches a fixed world target (position, optionally rotation)."""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any, ClassVar

import numpy as np
import torch

from engine.constraints.base import Constraint, joint_index, rotation_distance, vec
from engine.solver.state import PoseState


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
    joint: str = "lwrist"
    position: np.ndarray = field(default_factory=lambda: np.array([0.3, -0.3, 1.2]))
    rotation: np.ndarray = field(default_factory=lambda: np.array([1.0, 0.0, 0.0, 0.0]))
    use_rotation: bool = False
    rotation_weight: float = 0.1
    tolerance: float = 0.01

    def check(self) -> None:
        joint_index(self.joint, "joint", self.kind)

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

    def gizmo(self, positions: np.ndarray | None = None) -> dict[str, Any]:
        return {"type": "point", "position": np.asarray(self.position, float).copy(), "edit": "position"}
