"""``balance``: keep the upper body over its support.

``mode = "head_over_hip"``: horizontal distance between the ground projections of the
head (``upperneck``) and the root. ``mode = "com_over_feet"``: horizontal distance
between a centre-of-mass proxy (the mean of all joint positions) and the midpoint of
the ankles. Distances within ``tolerance`` cost nothing; beyond it the loss is the
squared excess (metres squared).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, ClassVar

import numpy as np
import torch

from engine import skeleton as sk
from engine.constraints.base import Constraint
from engine.errors import UserError
from engine.solver.state import PoseState

MODES = ("head_over_hip", "com_over_feet")
_HEAD, _ROOT = sk.JOINT_INDEX["upperneck"], sk.JOINT_INDEX["root"]
_FEET = [sk.JOINT_INDEX["lankle"], sk.JOINT_INDEX["rankle"]]


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
    choices: ClassVar[dict[str, tuple[str, ...]]] = {"mode": MODES}
    mode: str = "head_over_hip"
    tolerance: float = 0.05

    def check(self) -> None:
        if self.mode not in MODES:
            raise UserError(f"constraint {self.kind!r}: field 'mode' must be one of {', '.join(MODES)}")
        if self.tolerance < 0:
            raise UserError(f"constraint {self.kind!r}: field 'tolerance' must be >= 0")

    def _distance(self, positions: torch.Tensor) -> torch.Tensor:
        if self.mode == "head_over_hip":
            a, b = positions[_HEAD, :2], positions[_ROOT, :2]
        else:
            a, b = positions[:, :2].mean(0), positions[_FEET, :2].mean(0)
        return ((a - b) ** 2).sum().clamp_min(1e-12).sqrt()

    def loss(self, state: PoseState) -> torch.Tensor:
        return torch.relu(self._distance(state.positions) - self.tolerance).pow(2)

    def satisfied(self, state: PoseState) -> bool:
        return float(self._distance(state.positions.detach())) <= self.tolerance + 0.01

    def gizmo(self, positions: np.ndarray | None = None) -> dict[str, Any]:
        if positions is None:
            return {}
        p = np.asarray(positions, float)
        if self.mode == "head_over_hip":
            a, b = p[_HEAD].copy(), p[_ROOT].copy()
        else:
            a, b = p.mean(0), p[_FEET].mean(0)
        a[2] = b[2] = 0.0
        return {"type": "line", "points": np.stack([a, b])}
