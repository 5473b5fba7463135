"""Joint targets: where the user wants a joint (and optionally how turned), as solver terms.

A target is a :class:`engine.constraints.SensorConstraint` named ``target:<joint>``: a
3-DoF one for a position, a 6-DoF one with a rotation. Sensors are what the solver's fast
path evaluates itself, so a pose with only targets solves there.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np

from engine import skeleton as sk
from engine.constraints.sensor import SensorConstraint
from engine.errors import UserError
from engine.solver.limb_ik import LIMBS
from engine.validation import check_known_fields, shown

#: Accepted target weights (the GUI's 0-10 slider).
WEIGHT_RANGE = (0.0, 10.0)
#: Weight of a target's rotation term against its squared position error (m^2 per unit).
ROTATION_WEIGHT = 0.1


@dataclass
class JointTarget:
    """A wish for one joint.

    Attributes
    ----------
    joint : str
        Canonical joint name.
    position : ndarray (3,)
        World target, metres.
    rotation : ndarray (4,) or None
        World rotation (w, x, y, z), or None for a position target.
    weight : float
        In :data:`WEIGHT_RANGE`; 0 switches the target off without removing it.
    enabled : bool
    pelvis_only : bool
        On the root's target only: the pelvis alone goes there, the feet stay planted and
        the upper body keeps its pose relative to it (:mod:`engine.authoring.pelvis_drag`).
    """

    joint: str
    position: np.ndarray
    rotation: np.ndarray | None = None
    weight: float = 1.0
    enabled: bool = True
    pelvis_only: bool = False

    def __post_init__(self) -> None:
        if self.joint not in sk.JOINT_INDEX:
            raise UserError(f"target: unknown joint {shown(self.joint)}")
        if not isinstance(self.pelvis_only, bool):
            raise UserError(f"target {self.joint}: field 'pelvis_only' must be true or false")
        if self.pelvis_only and self.joint != "root":
            raise UserError(f"target {self.joint}: field 'pelvis_only' is for the root's target only")
        self.position = _numbers(self.position, 3, f"target {self.joint}: position")
        if self.rotation is not None:
            q = _numbers(self.rotation, 4, f"target {self.joint}: rotation")
            n = float(np.linalg.norm(q))
            if n < 1e-9:
                raise UserError(f"target {self.joint}: rotation must be a non-zero quaternion (w, x, y, z)")
            self.rotation = q / n
        if (
            isinstance(self.weight, bool)
            or not isinstance(self.weight, (int, float))
            or not (WEIGHT_RANGE[0] <= float(self.weight) <= WEIGHT_RANGE[1])
        ):
            raise UserError(f"target {self.joint}: weight must be a number in {WEIGHT_RANGE[0]:g}-{WEIGHT_RANGE[1]:g}")
        self.weight = float(self.weight)

    @property
    def index(self) -> int:
        return sk.JOINT_INDEX[self.joint]

    @property
    def active(self) -> bool:
        return self.enabled and self.weight > 0

    def constraint(self) -> SensorConstraint:
        """The solver term of this target."""
        six = self.rotation is not None
        return SensorConstraint(
            name=f"target:{self.joint}",
            weight=self.weight,
            enabled=self.active,
            joint=self.joint,
            dof=6 if six else 3,
            position=self.position.copy(),
            rotation=self.rotation.copy() if self.rotation is not None else np.array([1.0, 0.0, 0.0, 0.0]),
            rotation_weight=ROTATION_WEIGHT,
        )

    def to_dict(self) -> dict:
        out: dict = {"position": [float(x) for x in self.position]}
        if self.rotation is not None:
            out["rotation"] = [float(x) for x in self.rotation]
        if self.weight != 1.0:
            out["weight"] = self.weight
        if not self.enabled:
            out["enabled"] = False
        if self.pelvis_only:
            out["pelvis_only"] = True
        return out


def pelvis_only_target(targets: Mapping[str, JointTarget]) -> JointTarget | None:
    """The root's target in ``targets`` when it is active and moves the pelvis alone
    (``pelvis_only``), else None."""
    t = targets.get("root")
    return t if t is not None and t.active and t.pelvis_only else None


def target_from_json(joint: str, value, where: str) -> JointTarget:
    """A target from scene JSON: ``[x, y, z]`` or ``{"position": [...], "rotation": [...],
    "weight": w, "enabled": b, "pelvis_only": b}``; errors are prefixed with ``where``."""
    try:
        if isinstance(value, dict):
            check_known_fields(value, ("position", "rotation", "weight", "enabled", "pelvis_only"), "target")
            if "position" not in value:
                raise UserError("field 'position' is missing")
            enabled = value.get("enabled", True)
            if not isinstance(enabled, bool):
                raise UserError("field 'enabled' must be true or false")
            pelvis_only = value.get("pelvis_only", False)
            return JointTarget(
                joint, value["position"], value.get("rotation"), value.get("weight", 1.0), enabled, pelvis_only
            )
        return JointTarget(joint, value)
    except UserError as exc:
        raise UserError(f"{where}: {exc}") from None


def solve_inputs(
    targets: "list[JointTarget]",
) -> tuple[list[SensorConstraint], dict[int, np.ndarray], dict[int, np.ndarray]]:
    """Solver terms, exact limb targets (wrists, ankles) and exact rotations of the
    active ``targets``."""
    live = [t for t in targets if t.active]
    reach = {t.index: t.position for t in live if t.index in LIMBS}
    rotations = {t.index: t.rotation for t in live if t.rotation is not None}
    return [t.constraint() for t in live], reach, rotations


def _numbers(value, n: int, where: str) -> np.ndarray:
    try:
        a = np.asarray(value, dtype=np.float64).reshape(-1)
    except (TypeError, ValueError):
        raise UserError(f"{where} must be {n} numbers") from None
    if a.size != n or not all(math.isfinite(x) for x in a):
        raise UserError(f"{where} must be {n} finite numbers, got {shown(value)}")
    return a
