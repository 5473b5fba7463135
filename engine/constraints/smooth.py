"""``smooth``: joints keep their velocity from the previous two frames (a jitter damper).

Loss: mean over the 22 joints of ``|p_j - target_j|^2`` (metres squared), where the
method sets ``target = p(t-1) + (p(t-1) - p(t-2))`` every frame, the constant-velocity
extrapolation of the previous two solved poses. It penalises each joint's acceleration
(``|a| dt^2``), not its velocity, so steady motion is not held back; only a change of
velocity costs. Zero until two frames have been solved (``target`` NaN). The residual
is ``(p - target) / sqrt(22)``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import ClassVar

import numpy as np

from engine import skeleton as sk
from engine.constraints.base import Constraint
from engine.constraints.residual import FrameInputs, PointTerm

_EVERY = tuple(range(sk.NUM_JOINTS))


@dataclass
class SmoothConstraint(Constraint):
    """Constant-velocity prior on every joint's world position.

    Attributes
    ----------
    target : ndarray (22, 3)
        Extrapolated joint positions, metres; NaN = no target yet. Set per frame by
        :meth:`set_history`; runtime state, not a saved parameter.
    """

    kind: ClassVar[str] = "smooth"
    user_facing: ClassVar[bool] = False  # built by DragPoser from its own past poses

    def __post_init__(self) -> None:
        super().__post_init__()
        self.target = np.full((sk.NUM_JOINTS, 3), np.nan)

    def set_history(self, previous: np.ndarray | None, before: np.ndarray | None) -> None:
        """Target from the last two solved poses ``(22, 3)`` (None: not available yet)."""
        if previous is None or before is None:
            self.target = np.full((sk.NUM_JOINTS, 3), np.nan)
        else:
            self.target = 2.0 * np.asarray(previous, dtype=np.float64) - np.asarray(before, dtype=np.float64)

    def acts_on(self) -> tuple[str, ...]:
        return tuple(sk.JOINT_NAMES)

    def term(self, frame: FrameInputs) -> PointTerm:
        """``(P - target) / sqrt(22)`` over every joint (66 entries), so the loss is the mean
        squared distance to the constant-velocity target; zero while there is none."""
        n, on = sk.NUM_JOINTS, 1.0 if self.active else 0.0
        return PointTerm(self.name, _EVERY, self.target if self.active else np.zeros((n, 3)), on / math.sqrt(n))

    @classmethod
    def examples(cls, positions: np.ndarray) -> list[Constraint]:
        moving = cls(weight=3.0)
        moving.set_history(positions + 0.03, positions)
        return [moving]

    @property
    def active(self) -> bool:
        return bool(np.isfinite(self.target).all())
