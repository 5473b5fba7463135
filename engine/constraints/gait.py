"""``gait``: the ankles meet the gait planner's stance and swing targets (legs that step).

Built by DragPoser for sensor sets without foot trackers: every frame the method hands it
the :class:`engine.solver.gait.GaitPlanner`'s targets (:meth:`GaitConstraint.set_targets`):
the stance ankle's planted position and the swing ankle's point on its way to its landing
spot, horizontal only, both weighted by how fast the body travels (zero when it does not),
and, where the standing-legs pull is on, each ankle under its hip joint while the body
travels slowly (the term is off when neither acts). Loss (metres squared): ``sum_k |scale_k * (P_k - target_k)|^2``
over the two ankles, per axis. Residual: ``scale * (P_ankles - target)``, 6 entries.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar

import numpy as np

from engine import skeleton as sk
from engine.constraints.base import Constraint
from engine.constraints.residual import FrameInputs, PointTerm

#: The ankles the term steers: left, right.
ANKLES = (sk.JOINT_INDEX["lankle"], sk.JOINT_INDEX["rankle"])


@dataclass
class GaitTargets:
    """One frame's targets: ``target (2, 3)`` world ankle positions (left, right), metres,
    and ``scale (2, 3)``, the square roots of their weights per axis (0: not targeted)."""

    target: np.ndarray
    scale: np.ndarray
    stance: int | None = None  # 0 left, 1 right, None while off
    phase: float = 0.0

    @classmethod
    def off(cls) -> "GaitTargets":
        return cls(np.zeros((2, 3)), np.zeros((2, 3)))

    @property
    def active(self) -> bool:
        return bool(np.any(self.scale > 0.0))


@dataclass
class GaitConstraint(Constraint):
    """The ankles' pull towards the gait planner's targets (no parameters of its own).

    Attributes
    ----------
    targets : GaitTargets
        This frame's targets, set by the method (:meth:`set_targets`); runtime state, not
        a saved parameter. Off (all scales 0) until set.
    """

    kind: ClassVar[str] = "gait"
    user_facing: ClassVar[bool] = False  # built by DragPoser from its trackers' travel

    def __post_init__(self) -> None:
        super().__post_init__()
        self.targets = GaitTargets.off()

    def set_targets(self, targets: GaitTargets) -> None:
        self.targets = targets

    def acts_on(self) -> tuple[str, ...]:
        return ("lankle", "rankle")

    def term(self, frame: FrameInputs) -> PointTerm:
        """``scale * (P_ankles - target)``, 6 entries (all scales zero: the term is off)."""
        return PointTerm(self.name, ANKLES, self.targets.target, self.targets.scale)

    @classmethod
    def examples(cls, positions: np.ndarray) -> list[Constraint]:
        walking = cls(weight=2.0)
        target = positions[list(ANKLES)] + [[0.1, -0.05, 0.0], [-0.2, 0.1, 0.0]]
        walking.set_targets(GaitTargets(target, np.array([[1.0, 1.0, 0.0], [0.5, 0.5, 0.0]]), stance=0))
        return [walking, cls(name="standing")]
