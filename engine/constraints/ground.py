"""``ground``: the lower foot stays near the floor (sparse sensor sets without foot trackers).

Loss (metres squared): with ``z`` the height of the lower ankle (``lankle`` / ``rankle``)
above the floor at z = 0 (a soft minimum of the two, within 1.4 cm of the lower one;
``engine.solver.pose_terms.SOFTMIN_TAU``), ``relu(z - high)^2 + relu(low - z)^2``. Standing, walking and
dancing keep one ankle 4-18 cm above the floor (5th-95th percentile on the validation
clips), so the band penalises a body floating above the floor or sunk into it: with the
hips or head tracked, the legs must bend to reach the floor. DragPoser (sec. 5.1) adds a
similar "feet near the floor" loss for its three-sensor sets. The solver's fast path
evaluates the same term (:mod:`engine.solver.pose_terms`).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar

import torch

from engine import skeleton as sk
from engine.constraints.base import Constraint
from engine.solver.pose_terms import SOFTMIN_TAU
from engine.solver.state import PoseState

_FEET = [sk.JOINT_INDEX["lankle"], sk.JOINT_INDEX["rankle"]]


@dataclass
class GroundConstraint(Constraint):
    """The lower ankle's height within ``[low, high]`` metres.

    Parameters
    ----------
    low, high : float
        Band of the lower ankle's height above the floor, metres.
    """

    kind: ClassVar[str] = "ground"
    user_facing: ClassVar[bool] = False  # built by DragPoser for sets without foot trackers
    low: float = 0.05
    high: float = 0.14

    def loss(self, state: PoseState) -> torch.Tensor:
        z = -SOFTMIN_TAU * torch.logsumexp(-state.positions[_FEET, 2] / SOFTMIN_TAU, dim=0)
        return torch.relu(z - self.high) ** 2 + torch.relu(self.low - z) ** 2
