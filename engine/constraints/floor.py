"""``floor``: feet stay above the floor and do not slide while in contact.

Two terms, summed over the listed joints (ankles and toes by default):

* **penetration**: ``relu(floor_height + clearance - z)^2`` (metres squared);
* **sliding**: ``slide_weight * |xy - xy_prev|^2`` for joints whose previous-frame
  height was below ``contact_height`` (a planted foot should not skate). The contact
  test uses the previous frame only, so it is a fixed mask within a solve.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, ClassVar

import numpy as np
import torch

from engine.constraints.base import Constraint, joint_index
from engine.errors import UserError
from engine.solver.state import PoseState


@dataclass
class FloorConstraint(Constraint):
    """Feet not below the floor and planted when near it.

    Parameters
    ----------
    joints : tuple of str
        Joints kept above the floor (default ankles and toes).
    floor_height : float
        Height of the floor plane, metres (z).
    clearance : float
        Minimum height of the joints above the floor, metres.
    contact_height : float
        A joint whose previous height was below this is in contact, metres.
    slide_weight : float
        Weight of the sliding term relative to the penetration term.
    """

    kind: ClassVar[str] = "floor"
    joints: tuple[str, ...] = ("lankle", "rankle", "ltoe", "rtoe")
    floor_height: float = 0.0
    clearance: float = 0.0
    contact_height: float = 0.08
    slide_weight: float = 1.0

    def check(self) -> None:
        if isinstance(self.joints, str):
            self.joints = tuple(j.strip() for j in self.joints.split(",") if j.strip())
        self.joints = tuple(self.joints)
        if not self.joints:
            raise UserError(f"constraint {self.kind!r}: field 'joints' lists no joint")
        for j in self.joints:
            joint_index(j, "joints", self.kind)

    def _index(self) -> list[int]:
        return [joint_index(j, "joints", self.kind) for j in self.joints]

    def loss(self, state: PoseState) -> torch.Tensor:
        idx = self._index()
        p = state.positions[idx]
        out = torch.relu(self.floor_height + self.clearance - p[:, 2]).pow(2).sum()
        if state.previous_positions is not None and self.slide_weight > 0:
            prev = state.previous_positions[idx].detach()
            contact = (prev[:, 2] < self.floor_height + self.contact_height).to(p.dtype)
            slide = ((p[:, :2] - prev[:, :2]) ** 2).sum(-1)
            out = out + self.slide_weight * (contact * slide).sum()
        return out

    def satisfied(self, state: PoseState) -> bool:
        z = state.positions[self._index(), 2].detach()
        return bool((z >= self.floor_height + self.clearance - 0.01).all())

    def gizmo(self, positions: np.ndarray | None = None) -> dict[str, Any]:
        if self.floor_height == 0.0:
            return {}  # the viewport already draws the z = 0 floor
        lo = np.array([-2.0, -2.0, self.floor_height - 0.005])
        hi = np.array([2.0, 2.0, self.floor_height])
        return {"type": "box", "min": lo, "max": hi}
