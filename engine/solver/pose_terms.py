"""Whole-pose loss terms of the solver's fast path, with their closed-form gradients (numpy).

Each term reads the frame's world joint positions ``P (22, 3)`` (after the root anchor)
and adds its gradient w.r.t. ``P`` to the position gradient that
:meth:`engine.solver.fast.FastPose.backward` propagates through FK and the decoder. The
reference path computes the same losses with autograd from the constraint classes
(``engine/constraints/smooth.py``, ``ground.py``); a test compares the two.
"""

from __future__ import annotations

import math
from typing import Protocol

import numpy as np

from engine import skeleton as sk


class PoseTerm(Protocol):
    """A fast-path term: ``name``, ``weight``, unweighted ``loss(P)`` and its weighted
    gradient added in place by ``add_gradient(g_pos, P)``."""

    name: str
    weight: float

    def loss(self, pos: np.ndarray) -> float: ...

    def add_gradient(self, g_pos: np.ndarray, pos: np.ndarray) -> None: ...


class SmoothTerm:
    """``weight * mean_j |P_j - target_j|^2`` (the ``smooth`` constraint).

    Parameters
    ----------
    name : str
        Constraint name (loss reporting).
    weight : float
    target : ndarray (22, 3) or None
        Constant-velocity extrapolation of the last two poses, metres; None = inactive
        (loss and gradient zero).
    """

    def __init__(self, name: str, weight: float, target: np.ndarray | None) -> None:
        self.name, self.weight = name, float(weight)
        self.target = None if target is None else np.asarray(target, dtype=np.float64)

    @classmethod
    def of(cls, constraint) -> "SmoothTerm":
        """From a :class:`~engine.constraints.smooth.SmoothConstraint`."""
        return cls(constraint.name, constraint.weight, constraint.target if constraint.active else None)

    def loss(self, pos: np.ndarray) -> float:
        """Unweighted loss at positions ``pos (22, 3)``."""
        if self.target is None:
            return 0.0
        d = pos - self.target
        return float((d * d).sum() / len(pos))

    def add_gradient(self, g_pos: np.ndarray, pos: np.ndarray) -> None:
        """``g_pos (22, 3) += d (weight * loss) / d pos`` in place."""
        if self.target is not None:
            g_pos += (2.0 * self.weight / len(pos)) * (pos - self.target)


_FEET = np.array([sk.JOINT_INDEX["lankle"], sk.JOINT_INDEX["rankle"]])
#: Softness of the ``ground`` term's minimum over the two ankles, metres.
SOFTMIN_TAU = 0.02


class GroundTerm:
    """``weight * (relu(z - high)^2 + relu(low - z)^2)`` for ``z`` the soft minimum of the
    two ankle heights (the ``ground`` constraint): one foot stays within a band above the
    floor.

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
        self.name, self.weight, self.low, self.high = name, float(weight), float(low), float(high)

    @classmethod
    def of(cls, constraint) -> "GroundTerm":
        """From a :class:`~engine.constraints.ground.GroundConstraint`."""
        return cls(constraint.name, constraint.weight, constraint.low, constraint.high)

    def _excess(self, pos: np.ndarray) -> tuple[np.ndarray, float]:
        """Softmin weights of the two ankles ``(2,)`` and the soft height's excess over the band."""
        h = pos[_FEET, 2]
        m = h.min()
        e = np.exp(-(h - m) / SOFTMIN_TAU)
        z = m - SOFTMIN_TAU * math.log(e.sum())
        return e / e.sum(), (z - self.high if z > self.high else (z - self.low if z < self.low else 0.0))

    def loss(self, pos: np.ndarray) -> float:
        return self._excess(pos)[1] ** 2

    def add_gradient(self, g_pos: np.ndarray, pos: np.ndarray) -> None:
        w, e = self._excess(pos)
        g_pos[_FEET, 2] += (2.0 * self.weight * e) * w


#: Constraint kind -> its fast-path term built from the constraint.
POSE_TERMS = {"smooth": SmoothTerm.of, "ground": GroundTerm.of}
