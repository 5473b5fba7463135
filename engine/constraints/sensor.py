"""``sensor``: a tracker on a joint (DragPoser's sparse input, sec. 4.4).

The loss is the squared position error (metres squared, summed over x, y, z) plus, for a
6-DoF tracker, ``rotation_weight * (1 - <q, q_target>^2)``: a sign-invariant rotation
distance equal to ``sin^2(angle / 2)`` (about ``angle^2 / 4`` for small errors).
The method updates the target every frame with :meth:`SensorConstraint.set_target`.
Every tracker of a frame is one :class:`SensorTerm` (one set of array operations), which
the batched offline solve gives a frame axis.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass
from typing import Any, ClassVar

import numpy as np

from engine.constraints.base import Constraint, OnOneJoint, joint_index, param
from engine.constraints.residual import FrameInputs, FrameRows, Kit, Residuals, Term
from engine.constraints.rotation_residual import entry_block, rotation_residual
from engine.errors import UserError
from engine.gizmos import PointGizmo
from engine.kinematics import quat_np as QN


@dataclass
class SensorConstraint(OnOneJoint, Constraint):
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
        super().check()
        if self.dof not in (3, 6):
            raise UserError(f"constraint {self.kind!r}: field 'dof' must be 3 or 6, got {self.dof!r}")

    def set_target(self, position: np.ndarray, rotation: np.ndarray | None = None, connected: bool = True) -> None:
        """New tracker reading for the next solve (metres; (w, x, y, z))."""
        self.position = np.asarray(position, dtype=np.float64).reshape(3)
        if rotation is not None:
            self.rotation = np.asarray(rotation, dtype=np.float64).reshape(4)
        self.connected = bool(connected)

    def term(self, frame: FrameInputs) -> "SensorTerm":
        return SensorTerm([self])

    @classmethod
    def terms(cls, items: list[Constraint], frame: FrameInputs) -> list[Term]:
        """Every tracker of the frame in one term (one set of array operations)."""
        return [SensorTerm(items)] if items else []  # type: ignore[arg-type]

    @classmethod
    def examples(cls, positions: np.ndarray) -> list[Constraint]:
        p = lambda j: positions[joint_index(j)]  # noqa: E731
        turn = np.array([math.cos(0.4), 0.3 * math.sin(0.4), math.sin(0.4) * 0.9, 0.3 * math.sin(0.4)])
        return [
            cls(name="head", joint="upperneck", position=p("upperneck") + [0.05, -0.1, 0.02], rotation=turn),
            cls(name="hand", joint="lwrist", dof=3, position=p("lwrist") + [0.1, 0.0, -0.05], weight=2.0),
            cls(name="lost", joint="rwrist", position=p("rwrist") + [0.2, 0.0, 0.0], connected=False),
            cls(
                name="hip",
                joint="root",
                position=p("root") + [0.0, 0.03, 0.0],
                rotation=turn[[0, 2, 1, 3]],
                rotation_weight=0.5,
            ),
        ]

    def gizmo(self, positions: np.ndarray | None = None) -> PointGizmo | None:
        position = np.asarray(self.position, float)
        return PointGizmo(position) if np.all(np.isfinite(position)) else None


def unit_rotation(q: Any) -> np.ndarray:
    """A tracker's rotation ``(4,)`` as the sensor term takes it: float64, unit length
    (a zero quaternion stays finite)."""
    q = np.asarray(q, dtype=np.float64)
    return q / max(float(np.linalg.norm(q)), 1e-12)


class SensorTerm(FrameRows, Term):
    """The residual of the trackers ``items`` over ``A`` frames: per tracker
    ``on * (P_j - t)`` (3 entries) and, for a 6-DoF one, ``on * sqrt(rotation_weight / 8)
    * (W_j - T)`` (9 entries: :func:`~engine.constraints.rotation_residual.rotation_residual`), so
    its loss is the squared position error plus ``rotation_weight * sin^2(angle / 2)``.

    The targets carry a frame axis (``target (A, S, 3)``, ``rot_target (A, S6, 3, 3)``,
    ``on (A, S)``, ``scale (A, S6)``) so the batched offline solve gives each frame its
    readings (:class:`~engine.constraints.residual.FrameRows`); built from the
    constraints they hold one frame.
    """

    PER_FRAME = ("target", "on", "rot_target", "scale")

    def __init__(self, items: list[SensorConstraint]) -> None:
        self.names = tuple(c.name for c in items)
        (self.joints, self.six, self.joints6, self.owner, self.check_group, self.entry_joint, self._unit) = _layout(
            tuple((c.joint, c.dof, c.kind) for c in items)
        )
        six = self.six.tolist()
        self.target = np.array([c.position for c in items], dtype=np.float64).reshape(1, -1, 3)
        self.on = np.array([[float(c.connected) for c in items]]).reshape(1, -1)
        rot = np.array([unit_rotation(items[k].rotation) for k in six]).reshape(-1, 4)
        self.rot_target = QN.unit_to_matrix(rot).reshape(1, -1, 3, 3)
        self.scale = np.array([[math.sqrt(items[k].rotation_weight / 8.0) for k in six]]).reshape(1, -1)
        self.pos_tol2 = np.array([c.position_tolerance**2 for c in items])
        self.rot_tol = np.array([math.sin(math.radians(items[k].rotation_tolerance) / 2) ** 2 for k in six])

    def residual(self, kit: Kit, P: Any, W: Any, z: Any, jac: bool = False, rows: Any = None) -> Residuals:
        sel = self.select(P, rows)
        on = kit.const(self.on[sel], P)
        a = P.shape[0]
        err = (kit.joints(P, self.joints) - kit.const(self.target[sel], P)) * on[..., None]
        parts, d_rot, rows6 = [err.reshape(a, -1)], None, None
        if len(self.six):
            scale = self.kept("scale", sel, lambda: self.scale[sel] * self.on[sel][:, self.six])
            if jac:  # a block whose position rows stay zero; its rotation rows are written in place
                d_rot, rows6 = self.kept(
                    "d_rot", sel, lambda: entry_block((a, len(self.owner), 3), 3 * len(self.joints))
                )
            W6, T6 = kit.joints(W, self.joints6), kit.const(self.rot_target[sel], P)
            parts.append(rotation_residual(kit, W6, T6, kit.const(scale, P), jac, rows6)[0])
        r = kit.cat(parts, -1) if len(parts) > 1 else parts[0]
        if not jac:
            return Residuals(r)
        d_pos = self.kept("d_pos", sel, lambda: self._position_jacobian(sel))
        return Residuals(r, entry_joint=self.entry_joint, d_pos_entry=d_pos, d_rot_entry=d_rot)

    def _position_jacobian(self, sel: Any) -> np.ndarray:
        """``(A, m, 3)``: ``on`` times each position entry's unit direction, zero rows for
        the rotation entries (constant within a frame)."""
        on = self.on[sel]
        d_pos = np.zeros((len(on), len(self.entry_joint), 3))
        d_pos[:, : 3 * len(self.joints)] = self._unit * np.repeat(on, 3, axis=1)[:, :, None]
        return d_pos

    def check_limits(self, sel: Any) -> np.ndarray:
        """Position: the squared tolerance. Rotation: ``|r|^2 = scale^2 |W - T|_F^2 = 8 scale^2
        sin^2(angle / 2)``, so the bound is ``8 scale^2`` times the tolerance's ``sin^2``
        (a rotation with zero weight does not hold the stop). A tracker that is off has a
        zero residual."""
        scale = self.scale[sel]
        rot = 8.0 * scale * scale * self.rot_tol
        return np.concatenate([np.broadcast_to(self.pos_tol2, (len(scale), len(self.pos_tol2))), rot], axis=1)


@functools.lru_cache(maxsize=64)
def _layout(trackers: tuple[tuple[str, int, str], ...]) -> tuple[np.ndarray, ...]:
    """The index arrays of a :class:`SensorTerm` over trackers ``(joint, dof, kind)``, which
    depend on nothing else: built once per tracker set, shared by its terms (read only).

    Returns ``(joints, six, joints6, owner, check_group, entry_joint, unit)``: each tracker's
    joint, the 6-DoF trackers' places and joints, each residual entry's tracker, its
    satisfaction group (each tracker's position, 3 entries, then each 6-DoF one's rotation,
    9), the joint it reads, and the position entries' unit directions ``(3 S, 3)``."""
    joints = np.array([joint_index(j, "joint", kind) for j, _, kind in trackers], dtype=np.intp)
    six = np.array([k for k, (_, dof, _) in enumerate(trackers) if dof == 6], dtype=np.intp)
    joints6 = joints[six]
    s = len(trackers)
    owner = np.concatenate([np.repeat(np.arange(s), 3), np.repeat(six, 9)]).astype(np.intp)
    check_group = np.concatenate([np.repeat(np.arange(s), 3), s + np.repeat(np.arange(len(six)), 9)])
    entry_joint = np.concatenate([np.repeat(joints, 3), np.repeat(joints6, 9)]).astype(np.intp)
    return joints, six, joints6, owner, check_group, entry_joint, np.tile(np.eye(3), (s, 1))
