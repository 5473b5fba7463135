"""``smooth``: joints keep their velocity from the previous two frames (a jitter damper).

Loss: mean over the 22 joints of ``|p_j - target_j|^2`` (metres squared), where the
method sets ``target = p(t-1) + (p(t-1) - p(t-2))`` every frame, the constant-velocity
extrapolation of the previous two solved poses. It penalises each joint's acceleration
(``|a| dt^2``), not its velocity, so steady motion is not held back; only a change of
velocity costs. Zero until two frames have been solved (``target`` NaN). Fast path: the
gradient is ``2 (p_j - target_j) / 22`` per joint.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar, TYPE_CHECKING

import numpy as np

from engine import skeleton as sk
from engine.constraints.base import Constraint, param, vec
from engine.constraints.terms import FrameInputs

if TYPE_CHECKING:  # torch is imported by the code that runs a loss (the engine), not by editors
    import torch

    from engine.kinematics.pose_state import PoseState


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

    def fast_term(self, frame: FrameInputs) -> "SmoothTerm":
        return SmoothTerm(self.name, self.weight, self.target if self.active else None)

    @property
    def active(self) -> bool:
        return bool(np.isfinite(self.target).all())

    def loss(self, state: PoseState) -> torch.Tensor:
        if not self.active:
            return state.positions.new_zeros(())
        return ((state.positions - vec(self.target, state.positions)) ** 2).sum(-1).mean()


class SmoothTerm:
    """``weight * mean_j |P_j - target_j|^2``, the fast-path term of :class:`SmoothConstraint`.

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
        self.name, self.weight, self.turns = name, float(weight), False
        self.target = None if target is None else np.asarray(target, dtype=np.float64)

    def evaluate(self, pos: np.ndarray, world: np.ndarray, g_pos: np.ndarray, g_rot: np.ndarray) -> float:
        if self.target is None:
            return 0.0
        d = pos - self.target
        g_pos += (2.0 * self.weight / len(pos)) * d
        return float(np.einsum("ij,ij->", d, d) / len(pos))

    def satisfied(self, pos: np.ndarray, world: np.ndarray) -> bool:
        return True
