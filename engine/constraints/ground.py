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

from dataclasses import dataclass
from typing import Any, ClassVar

import numpy as np

from engine import skeleton as sk
from engine.constraints.base import Constraint, param
from engine.constraints.residual import FrameInputs, Kit, Residuals, Term

#: The joints whose lower height the band acts on.
FEET = [sk.JOINT_INDEX["lankle"], sk.JOINT_INDEX["rankle"]]
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

    def term(self, frame: FrameInputs) -> "GroundTerm":
        return GroundTerm(self.name, self.low, self.high)

    @classmethod
    def examples(cls, positions: np.ndarray) -> list[Constraint]:
        low = float(positions[FEET, 2].min())
        return [cls(weight=2.0, low=low + 0.3, high=low + 0.4), cls(low=low - 0.4, high=low - 0.3)]


class GroundTerm(Term):
    """``e`` with ``e^2 = relu(z - high)^2 + relu(low - z)^2`` for ``z`` the soft minimum
    of the two ankle heights: the residual of :class:`GroundConstraint`.

    ``z = -tau log(exp(-z_l / tau) + exp(-z_r / tau))`` with ``tau`` = :data:`SOFTMIN_TAU`:
    within ``tau ln 2`` of the lower ankle, and smooth where the feet swap (a hard minimum
    made the gradient jump between the feet from one iteration to the next). Its Jacobian
    on the ankles' heights is the softmin's weights inside the band's complement.

    Parameters
    ----------
    name : str
    low, high : float
        Band of the lower ankle's height, metres above the floor (z = 0).
    """

    def __init__(self, name: str, low: float, high: float) -> None:
        self.names, self.owner = (name,), np.zeros(1, dtype=np.intp)
        self.low, self.high = float(low), float(high)

    def residual(self, kit: Kit, P: Any, W: Any, z: Any, jac: bool = False, rows: Any = None) -> Residuals:
        h = P[:, FEET, 2]
        soft = -SOFTMIN_TAU * kit.logsumexp(-h / SOFTMIN_TAU, axis=-1)
        e = kit.relu(soft - self.high) - kit.relu(self.low - soft)
        if not jac:
            return Residuals(e[:, None])
        w = np.exp(-(h - h.min(1, keepdims=True)) / SOFTMIN_TAU)
        w /= w.sum(1, keepdims=True)
        d = np.zeros((len(P), 1, len(FEET), 3))
        d[:, 0, :, 2] = w * (e != 0.0)[:, None]
        return Residuals(e[:, None], np.array(FEET, dtype=np.intp), d)
