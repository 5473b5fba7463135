"""``smooth``: joints keep their velocity from the previous two frames (a jitter damper).

Loss: mean over the 22 joints of ``|p_j - target_j|^2`` (metres squared), where the
method sets ``target = p(t-1) + (p(t-1) - p(t-2))`` every frame, the constant-velocity
extrapolation of the previous two solved poses. It penalises each joint's acceleration
(``|a| dt^2``), not its velocity, so steady motion is not held back; only a change of
velocity costs. Zero until two frames have been solved (``target`` NaN). The solver's
fast path evaluates the same term itself (:mod:`engine.solver.pose_terms`).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar

import numpy as np
import torch

from engine import skeleton as sk
from engine.constraints.base import Constraint, vec
from engine.solver.state import PoseState


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

    @property
    def active(self) -> bool:
        return bool(np.isfinite(self.target).all())

    def loss(self, state: PoseState) -> torch.Tensor:
        if not self.active:
            return state.positions.new_zeros(())
        return ((state.positions - vec(self.target, state.positions)) ** 2).sum(-1).mean()
