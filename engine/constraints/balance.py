"""``balance``: keep the upper body over its support.

``mode = "head_over_hip"``: horizontal distance between the ground projections of the
head (``upperneck``) and the root. ``mode = "com_over_feet"``: horizontal distance
between a centre-of-mass proxy (the mean of all joint positions) and the midpoint of
the ankles. Distances within ``tolerance`` cost nothing; beyond it the loss is the
squared excess (metres squared).

Residual: ``relu(|a - b| - tolerance)`` for ``a``, ``b`` the two horizontal points; its
Jacobian w.r.t. ``a`` is ``(a - b) / |a - b|`` beyond the tolerance, spread over the joints
``a`` and ``b`` are means of.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, ClassVar

import numpy as np

from engine import skeleton as sk
from engine.constraints.base import Constraint, param
from engine.constraints.residual import FrameInputs, Kit, Residuals, Term
from engine.errors import UserError
from engine.gizmos import LineGizmo

MODES = ("head_over_hip", "com_over_feet")
_HEAD, _ROOT = sk.JOINT_INDEX["upperneck"], sk.JOINT_INDEX["root"]
_FEET = [sk.JOINT_INDEX["lankle"], sk.JOINT_INDEX["rankle"]]
_MIN_SQUARED = 1e-12  # m^2: the distance is clamped so its gradient stays finite
_SLACK = 0.01  # metres: satisfied this far beyond the tolerance


@dataclass
class BalanceConstraint(Constraint):
    """Upper body over the support, see the module doc.

    Parameters
    ----------
    mode : str
        ``head_over_hip`` or ``com_over_feet``.
    tolerance : float
        Allowed horizontal distance, metres.
    """

    kind: ClassVar[str] = "balance"
    mode: str = param("head_over_hip", editor="choice", choices=MODES)
    tolerance: float = param(0.05, editor="float", unit="m")

    def check(self) -> None:
        if self.mode not in MODES:
            raise UserError(f"constraint {self.kind!r}: field 'mode' must be one of {', '.join(MODES)}")
        if self.tolerance < 0:
            raise UserError(f"constraint {self.kind!r}: field 'tolerance' must be >= 0")

    def acts_on(self) -> tuple[str, ...]:
        return ("upperneck", "root") if self.mode == "head_over_hip" else tuple(sk.JOINT_NAMES)

    def term(self, frame: FrameInputs) -> "BalanceTerm":
        return BalanceTerm(self)

    @classmethod
    def examples(cls, positions: np.ndarray) -> list[Constraint]:
        return [cls(weight=3.0, tolerance=0.01), cls(mode="com_over_feet", tolerance=0.0)]

    @classmethod
    def placement(cls, params: dict[str, Any], positions: np.ndarray) -> dict[str, Any]:
        """Nothing to place: the rule is relative to the body."""
        return {}

    def gizmo(self, positions: np.ndarray | None = None) -> LineGizmo | None:
        if positions is None:
            return None
        p = np.asarray(positions, float)
        if self.mode == "head_over_hip":
            a, b = p[_HEAD].copy(), p[_ROOT].copy()
        else:
            a, b = p.mean(0), p[_FEET].mean(0)
        a[2] = b[2] = 0.0
        return LineGizmo(np.stack([a, b]))


class BalanceTerm(Term):
    """``relu(|a - b| - tolerance)`` for the two horizontal points of the mode, each a
    weighted sum of joints (:attr:`coef`: +1 or a mean's share for ``a``, minus for ``b``)."""

    def __init__(self, c: BalanceConstraint) -> None:
        self.names, self.owner = (c.name,), np.zeros(1, dtype=np.intp)
        self.tolerance = c.tolerance
        self.check_group, self.check_limit2 = np.zeros(1, dtype=np.intp), np.array([_SLACK**2])
        coef = np.zeros(sk.NUM_JOINTS)
        if c.mode == "com_over_feet":
            coef += 1.0 / sk.NUM_JOINTS
            coef[_FEET] -= 1.0 / len(_FEET)
        else:
            coef[_HEAD], coef[_ROOT] = 1.0, -1.0
        self.joints = np.flatnonzero(coef).astype(np.intp)
        self.coef = coef[self.joints]

    def _gap(self, kit: Kit, P: Any) -> tuple[Any, Any]:
        d = (P[:, self.joints, :2] * kit.const(self.coef, P)[:, None]).sum(1)  # (A, 2)
        return d, kit.sqrt(kit.clamp_min((d * d).sum(-1), _MIN_SQUARED))

    def residual(self, kit: Kit, P: Any, W: Any, z: Any, jac: bool = False, rows: Any = None) -> Residuals:
        d, dist = self._gap(kit, P)
        r = kit.relu(dist - self.tolerance)[:, None]
        if not jac:
            return Residuals(r)
        free = ((r[:, 0] > 0.0) & ((d * d).sum(-1) > _MIN_SQUARED)).astype(float)
        dd = np.zeros((len(P), 1, len(self.joints), 3))
        dd[:, 0, :, :2] = (free / dist)[:, None, None] * d[:, None, :] * self.coef[None, :, None]
        return Residuals(r, self.joints, dd)
