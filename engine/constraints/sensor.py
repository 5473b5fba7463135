"""``sensor``: a tracker on a joint (DragPoser's sparse input, sec. 4.4).

The loss is the squared position error (metres squared, summed over x, y, z) plus, for a
6-DoF tracker, ``rotation_weight * (1 - <q, q_target>^2)``: a sign-invariant rotation
distance equal to ``sin^2(angle / 2)`` (about ``angle^2 / 4`` for small errors).
The method updates the target every frame with :meth:`SensorConstraint.set_target`.
The solver's fast path batches every tracker of a frame into arrays (a :class:`NativeTerm`;
:class:`engine.solver.fast.FastTerms`).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any, ClassVar, TYPE_CHECKING

import numpy as np

from engine.constraints.base import Constraint, joint_index, param, rotation_distance, vec
from engine.constraints.terms import FrameInputs, NativeTerm
from engine.errors import UserError
from engine.gizmos import PointGizmo

if TYPE_CHECKING:  # torch is imported by the code that runs a loss (the engine), not by editors
    import torch

    from engine.kinematics.pose_state import PoseState


@dataclass
class SensorConstraint(Constraint):
    """Joint follows a tracker: position (3-DoF) or position and rotation (6-DoF).

    Parameters
    ----------
    joint : str
        Canonical joint the tracker is attached to.
    dof : int
        6 (position + rotation) or 3 (position only).
    position : ndarray (3,)
        Target world position, metres.
    rotation : ndarray (4,)
        Target world rotation (w, x, y, z); used with ``dof == 6``.
    connected : bool
        False while the tracker is lost; the loss is then zero.
    rotation_weight : float
        Weight of the rotation term relative to the position term (m^2 per unit).
    position_tolerance : float
        Metres; :meth:`satisfied` needs the error below it.
    rotation_tolerance : float
        Degrees; :meth:`satisfied` needs the 6-DoF rotation error below it.
    """

    kind: ClassVar[str] = "sensor"
    user_facing: ClassVar[bool] = False  # built by methods from the sensor readings
    joint: str = param("root", editor="joint")
    dof: int = param(6, editor="int")
    position: np.ndarray = param(factory=lambda: np.zeros(3), editor="vec3", unit="m")
    rotation: np.ndarray = param(factory=lambda: np.array([1.0, 0.0, 0.0, 0.0]), editor="quat")
    connected: bool = param(True, editor="bool")
    rotation_weight: float = param(0.1, editor="float")
    position_tolerance: float = param(0.01, editor="float", unit="m")
    rotation_tolerance: float = param(5.0, editor="float", unit="deg")

    def check(self) -> None:
        joint_index(self.joint, "joint", self.kind)
        if self.dof not in (3, 6):
            raise UserError(f"constraint {self.kind!r}: field 'dof' must be 3 or 6, got {self.dof!r}")

    def acts_on(self) -> tuple[str, ...]:
        return (self.joint,)

    def fast_term(self, frame: FrameInputs) -> NativeTerm:
        return NativeTerm(self, self.weight)

    def set_target(self, position: np.ndarray, rotation: np.ndarray | None = None, connected: bool = True) -> None:
        """New tracker reading for the next solve (metres; (w, x, y, z))."""
        self.position = np.asarray(position, dtype=np.float64).reshape(3)
        if rotation is not None:
            self.rotation = np.asarray(rotation, dtype=np.float64).reshape(4)
        self.connected = bool(connected)

    def _errors(self, state: PoseState) -> tuple[torch.Tensor, torch.Tensor | None]:
        j = joint_index(self.joint, "joint", self.kind)
        pos_err = ((state.positions[j] - vec(self.position, state.positions)) ** 2).sum()
        if self.dof != 6:
            return pos_err, None
        return pos_err, rotation_distance(state, j, self.rotation)

    def loss(self, state: PoseState) -> torch.Tensor:
        if not self.connected:
            return state.positions.new_zeros(())
        pos_err, rot_err = self._errors(state)
        return pos_err if rot_err is None else pos_err + self.rotation_weight * rot_err

    def satisfied(self, state: PoseState) -> bool:
        import torch
        if not self.connected:
            return True
        with torch.no_grad():
            pos_err, rot_err = self._errors(state)
            if float(pos_err) > self.position_tolerance**2:
                return False
            if rot_err is None:
                return True
            # rot_err = sin^2(angle / 2)
            return float(rot_err) <= math.sin(math.radians(self.rotation_tolerance) / 2) ** 2

    @classmethod
    def batch(cls, items: list[Constraint], like: torch.Tensor) -> Callable[[PoseState], torch.Tensor]:
        import torch
        from engine.kinematics import quaternion as Q
        idx = torch.tensor([joint_index(c.joint, "joint", cls.kind) for c in items])
        target = vec(np.stack([c.position for c in items]), like)
        on = vec([float(c.connected) for c in items], like)
        six = [k for k, c in enumerate(items) if c.dof == 6]
        rot_idx = idx[six]
        rot_w = vec([items[k].rotation_weight for k in six], like)
        quats = [unit_rotation(items[k].rotation) for k in six]  # no 6-DoF sensor (e.g. 6x3dof): none
        rot_t = Q.to_matrix(vec(np.stack(quats) if quats else np.zeros((0, 4)), like))
        six_t = torch.tensor(six, dtype=torch.long)

        def losses(state: PoseState) -> torch.Tensor:
            out = ((state.positions.index_select(0, idx) - target) ** 2).sum(-1)
            if len(six):
                r = _matrices(state, rot_idx)
                rot = ((3.0 - (rot_t * r).sum((-1, -2))) * 0.25).clamp(0.0, 1.0)
                out = out.index_add(0, six_t, rot_w * rot)
            return out * on

        return losses

    def gizmo(self, positions: np.ndarray | None = None) -> PointGizmo | None:
        position = np.asarray(self.position, float)
        return PointGizmo(position) if np.all(np.isfinite(position)) else None


def unit_rotation(q: Any) -> np.ndarray:
    """A tracker's rotation ``(4,)`` as the sensor term takes it: float64, unit length
    (a zero quaternion stays finite)."""
    q = np.asarray(q, dtype=np.float64)
    return q / max(float(np.linalg.norm(q)), 1e-12)


def _matrices(state: PoseState, idx: torch.Tensor) -> torch.Tensor:
    from engine.kinematics import quaternion as Q
    if state.rotation_matrices is not None:
        return state.rotation_matrices.index_select(0, idx)
    return Q.to_matrix(state.world_rotations().index_select(0, idx))
