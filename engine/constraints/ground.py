"""``ground``: the lower foot stays near the floor (sparse sensor sets without foot trackers).

Loss (metres squared): with ``z`` the height of the lower ankle (``lankle`` / ``rankle``)
above the floor at z = 0 (a soft minimum of the two, within 1.4 cm of the lower one;
:data:`SOFTMIN_TAU`), ``relu(z - high)^2 + relu(low - z)^2``. Standing, walking and
dancing keep one ankle 4-18 cm above the floor (5th-95th percentile on the validation
clips), so the band penalises a body floating above the floor or sunk into it: with the
hips or head tracked, the legs must bend to reach the floor. DragPoser (sec. 5.1) adds a
similar "feet near the floor" loss for its three-sensor sets.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import ClassVar, TYPE_CHECKING

import numpy as np

from engine import skeleton as sk
from engine.constraints.base import Constraint, param
from engine.constraints.terms import FrameInputs

if TYPE_CHECKING:  # torch is imported by the code that runs a loss (the engine), not by editors
    import torch

    from engine.kinematics.pose_state import PoseState

_FEET = [sk.JOINT_INDEX["lankle"], sk.JOINT_INDEX["rankle"]]
#: Softness of the minimum over the two ankles, metres.
SOFTMIN_TAU = 0.02


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
    low: float = param(0.05, editor="float", unit="m")
    high: float = param(0.14, editor="float", unit="m")

    def acts_on(self) -> tuple[str, ...]:
        return ("lankle", "rankle")

    def loss(self, state: PoseState) -> torch.Tensor:
        import torch
        z = -SOFTMIN_TAU * torch.logsumexp(-state.positions[_FEET, 2] / SOFTMIN_TAU, dim=0)
        return torch.relu(z - self.high) ** 2 + torch.relu(self.low - z) ** 2

    def fast_term(self, frame: FrameInputs) -> "GroundTerm":
        return GroundTerm(self.name, self.weight, self.low, self.high)


class GroundTerm:
    """``weight * (relu(z - high)^2 + relu(low - z)^2)`` for ``z`` the soft minimum of the
    two ankle heights: the fast-path term of :class:`GroundConstraint`.

    ``z = -tau log(exp(-z_l / tau) + exp(-z_r / tau))`` with ``tau`` = :data:`SOFTMIN_TAU`:
    within ``tau ln 2`` of the lower ankle, and smooth where the feet swap (a hard minimum
    made the gradient jump between the feet from one iteration to the next).

    Parameters
    ----------
    name : str
    weight : float
    low, high : float
        Band of the lower ankle's height, metres above the floor (z = 0).
    """

    def __init__(self, name: str, weight: float, low: float, high: float) -> None:
        self.name, self.weight, self.turns, self.low, self.high = name, float(weight), False, float(low), float(high)

    def _excess(self, pos: np.ndarray) -> tuple[np.ndarray, float]:
        """Softmin weights of the two ankles ``(2,)`` and the soft height's excess over the band."""
        h = pos[_FEET, 2]
        m = h.min()
        e = np.exp(-(h - m) / SOFTMIN_TAU)
        z = m - SOFTMIN_TAU * math.log(e.sum())
        return e / e.sum(), (z - self.high if z > self.high else (z - self.low if z < self.low else 0.0))

    def evaluate(self, pos: np.ndarray, world: np.ndarray, g_pos: np.ndarray, g_rot: np.ndarray) -> float:
        w, e = self._excess(pos)
        if e != 0.0:
            g_pos[_FEET, 2] += (2.0 * self.weight * e) * w
        return e * e

    def satisfied(self, pos: np.ndarray, world: np.ndarray) -> bool:
        return True
