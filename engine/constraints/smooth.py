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
from typing import Any, ClassVar

import numpy as np

from engine import skeleton as sk
from engine.constraints.base import Constraint
from engine.constraints.residual import FrameInputs, FrameRows, Kit, Residuals, Term


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

    def term(self, frame: FrameInputs) -> "SmoothTerm":
        return SmoothTerm(self.name, self.target if self.active else None)

    @classmethod
    def examples(cls, positions: np.ndarray) -> list[Constraint]:
        moving = cls(weight=3.0)
        moving.set_history(positions + 0.03, positions)
        return [moving]

    @property
    def active(self) -> bool:
        return bool(np.isfinite(self.target).all())


class SmoothTerm(FrameRows, Term):
    """``(P - target) / sqrt(22)`` over every joint (66 entries), so the loss is the mean
    squared distance to the constant-velocity target.

    Parameters
    ----------
    name : str
        Constraint name (loss reporting).
    target : ndarray (22, 3) or None
        Constant-velocity extrapolation of the last two poses, metres; None = inactive
        (residual zero). With a frame axis (``target (A, 22, 3)``, ``on (A,)``) in the
        batched solve.
    """

    PER_FRAME = ("target", "on")

    #: The same for every frame (shared, read only): each entry's constraint and joint, and
    #: ``(3 n, 3)`` the direction entry ``3 j + c`` reads ``P_j`` along, over ``sqrt(n)``.
    owner = np.zeros(3 * sk.NUM_JOINTS, dtype=np.intp)
    entry_joint = np.repeat(np.arange(sk.NUM_JOINTS), 3)
    _unit = np.tile(np.eye(3), (sk.NUM_JOINTS, 1)) / math.sqrt(sk.NUM_JOINTS)

    def __init__(self, name: str, target: np.ndarray | None) -> None:
        n = sk.NUM_JOINTS
        self.names = (name,)
        self.on = np.array([0.0 if target is None else 1.0])
        self.target = np.zeros((1, n, 3)) if target is None else np.asarray(target, dtype=np.float64).reshape(1, n, 3)

    def residual(self, kit: Kit, P: Any, W: Any, z: Any, jac: bool = False, rows: Any = None) -> Residuals:
        sel = self.select(P, rows)
        on = self.on[sel]
        a, n = P.shape[0], P.shape[1]
        r = ((P - kit.const(self.target[sel], P)) * kit.const(on / math.sqrt(n), P)[:, None, None]).reshape(a, 3 * n)
        if not jac:
            return Residuals(r)
        d_pos = self.kept("d_pos", sel, lambda: self._unit[None] * on[:, None, None])
        return Residuals(r, entry_joint=self.entry_joint, d_pos_entry=d_pos)
