"""``balance``: keep the upper body over its support.

``mode = "head_over_hip"``: horizontal distance between the ground projections of the
head (``upperneck``) and the root. ``mode = "com_over_feet"``: horizontal distance
between a centre-of-mass proxy (the mean of all joint positions) and the midpoint of
the ankles. Distances within ``tolerance`` cost nothing; beyond it the loss is the
squared excess (metres squared).

Fast path: with ``a``, ``b`` the two horizontal points and ``d = |a - b|``, the gradient
w.r.t. ``a`` is ``2 relu(d - tolerance) (a - b) / d``, spread over the joints ``a`` and
``b`` are means of.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, ClassVar, TYPE_CHECKING

import numpy as np

from engine import skeleton as sk
from engine.constraints.base import Constraint, param
from engine.constraints.terms import FrameInputs
from engine.errors import UserError
from engine.gizmos import LineGizmo

if TYPE_CHECKING:  # torch is imported by the code that runs a loss (the engine), not by editors
    import torch

    from engine.kinematics.pose_state import PoseState

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

    def _distance(self, positions: torch.Tensor) -> torch.Tensor:
        if self.mode == "head_over_hip":
            a, b = positions[_HEAD, :2], positions[_ROOT, :2]
        else:
            a, b = positions[:, :2].mean(0), positions[_FEET, :2].mean(0)
        return ((a - b) ** 2).sum().clamp_min(_MIN_SQUARED).sqrt()

    def loss(self, state: PoseState) -> torch.Tensor:
        import torch
        return torch.relu(self._distance(state.positions) - self.tolerance).pow(2)

    def satisfied(self, state: PoseState) -> bool:
        return float(self._distance(state.positions.detach())) <= self.tolerance + _SLACK

    def fast_term(self, frame: FrameInputs) -> "BalanceTerm":
        return BalanceTerm(self)

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


class BalanceTerm:
    """The fast-path term of one :class:`BalanceConstraint` (module doc)."""

    def __init__(self, c: BalanceConstraint) -> None:
        self.name, self.weight, self.turns = c.name, c.weight, False
        self.tolerance, self.com = c.tolerance, c.mode == "com_over_feet"

    def _gap(self, pos: np.ndarray) -> tuple[np.ndarray, float, bool]:
        if self.com:
            d = pos[:, :2].mean(0) - pos[_FEET, :2].mean(0)
        else:
            d = pos[_HEAD, :2] - pos[_ROOT, :2]
        s = float(d @ d)
        return d, math.sqrt(max(s, _MIN_SQUARED)), s > _MIN_SQUARED

    def evaluate(self, pos: np.ndarray, world: np.ndarray, g_pos: np.ndarray, g_rot: np.ndarray) -> float:
        d, dist, free = self._gap(pos)
        excess = dist - self.tolerance
        if excess <= 0.0:
            return 0.0
        if free:
            g = (2.0 * self.weight * excess / dist) * d  # d (weight loss) / d a, (2,)
            if self.com:
                g_pos[:, :2] += g / len(pos)
                g_pos[_FEET, :2] -= g / len(_FEET)
            else:
                g_pos[_HEAD, :2] += g
                g_pos[_ROOT, :2] -= g
        return excess * excess

    def satisfied(self, pos: np.ndarray, world: np.ndarray) -> bool:
        return self._gap(pos)[1] <= self.tolerance + _SLACK
