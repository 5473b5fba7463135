"""``look_at``: the head's forward axis points at a world point (DragPoser sec. 5.2).

The forward axis is given in the joint's own frame. In the canonical rest pose every
joint's world rotation is the identity and the character faces -Y, so the head's
(``upperneck``) forward axis is ``(0, -1, 0)``.

Fast path: with ``f = W_j axis`` and ``t = target - P_j``, ``loss = 1 - f.t / |t|`` has
``d loss / d P_j = (f - cos t/|t|) / |t|`` and rotation gradient ``-(f x t) / |t|``
(turning the joint by ``a`` moves ``f`` by ``a x f``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, ClassVar, TYPE_CHECKING

import numpy as np

from engine.constraints.base import Constraint, joint_index, param, vec, world_rotation_matrix
from engine.constraints.placement import LOOK_DISTANCE, facing, joint_at
from engine.constraints.terms import FrameInputs
from engine.errors import UserError
from engine.gizmos import LineGizmo, PointGizmo

if TYPE_CHECKING:  # torch is imported by the code that runs a loss (the engine), not by editors
    import torch

    from engine.kinematics.pose_state import PoseState

_MIN_DISTANCE = 1e-6  # metres: the direction to a target this close is not defined


@dataclass
class LookAtConstraint(Constraint):
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
        joint_index(self.joint, "joint", self.kind)
        if not np.linalg.norm(self.axis) > 1e-9:
            raise UserError(f"constraint {self.kind!r}: field 'axis' must be a non-zero vector")

    def acts_on(self) -> tuple[str, ...]:
        return (self.joint,)

    def _cos(self, state: PoseState) -> torch.Tensor:
        j = joint_index(self.joint, "joint", self.kind)
        axis = vec(self.axis / np.linalg.norm(self.axis), state.positions)
        forward = world_rotation_matrix(state, j) @ axis
        to_target = vec(self.target, state.positions) - state.positions[j]
        return (forward * to_target).sum() / to_target.norm().clamp_min(_MIN_DISTANCE)

    def loss(self, state: PoseState) -> torch.Tensor:
        return 1.0 - self._cos(state)

    def satisfied(self, state: PoseState) -> bool:
        import torch
        with torch.no_grad():
            c = float(self._cos(state))
        return c >= math.cos(math.radians(self.tolerance)) or not math.isfinite(c)

    def fast_term(self, frame: FrameInputs) -> "LookAtTerm":
        return LookAtTerm(self)

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


class LookAtTerm:
    """The fast-path term of one :class:`LookAtConstraint` (module doc)."""

    def __init__(self, c: LookAtConstraint) -> None:
        self.name, self.weight, self.turns = c.name, c.weight, True
        self.j = joint_index(c.joint, "joint", c.kind)
        self.axis = np.asarray(c.axis, dtype=np.float64) / np.linalg.norm(c.axis)
        self.target = np.asarray(c.target, dtype=np.float64)
        self.cos_tol = math.cos(math.radians(c.tolerance))

    def _parts(self, pos: np.ndarray, world: np.ndarray) -> tuple[list[float], list[float], float, float]:
        """Forward axis, direction to the target (unnormalised), its length and the
        cosine, in floats (numpy calls cost more than the arithmetic on three numbers)."""
        f = (world[self.j] @ self.axis).tolist()
        t = (self.target - pos[self.j]).tolist()
        n = max(math.sqrt(t[0] * t[0] + t[1] * t[1] + t[2] * t[2]), _MIN_DISTANCE)
        return f, t, n, (f[0] * t[0] + f[1] * t[1] + f[2] * t[2]) / n

    def evaluate(self, pos: np.ndarray, world: np.ndarray, g_pos: np.ndarray, g_rot: np.ndarray) -> float:
        (fx, fy, fz), (tx, ty, tz), n, c = self._parts(pos, world)
        k = self.weight / n
        s = c / n if n > _MIN_DISTANCE else 0.0  # below it the reference clamps |t|: the cosine is linear in t
        g_pos[self.j] += (k * (fx - s * tx), k * (fy - s * ty), k * (fz - s * tz))
        g_rot[self.j] -= (k * (fy * tz - fz * ty), k * (fz * tx - fx * tz), k * (fx * ty - fy * tx))  # k f x t
        return 1.0 - c

    def satisfied(self, pos: np.ndarray, world: np.ndarray) -> bool:
        c = self._parts(pos, world)[3]
        return c >= self.cos_tol or not math.isfinite(c)
