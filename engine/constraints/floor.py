"""``floor``: feet stay above the floor and do not slide while in contact.

Two terms, summed over the listed joints (ankles and toes by default):

* **penetration**: ``relu(floor_height + clearance - z)^2`` (metres squared);
* **sliding**: ``slide_weight * |xy - xy_prev|^2`` for joints whose previous-frame
  height was below ``contact_height`` (a planted foot should not skate). The contact
  test uses the previous frame only, so it is a fixed mask within a solve.

Fast path: gradient ``-2 relu(floor_height + clearance - z)`` on each joint's height and
``2 slide_weight (xy - xy_prev)`` on a planted joint's horizontal position.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, ClassVar, TYPE_CHECKING

import numpy as np

from engine.constraints.base import Constraint, joint_index, param
from engine.constraints.terms import FrameInputs
from engine.errors import UserError
from engine.gizmos import BoxGizmo

if TYPE_CHECKING:  # torch is imported by the code that runs a loss (the engine), not by editors
    import torch

    from engine.kinematics.pose_state import PoseState

_SLACK = 0.01  # metres: satisfied this far below the clearance


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
    joints: tuple[str, ...] = param(("lankle", "rankle", "ltoe", "rtoe"), editor="joints")
    floor_height: float = param(0.0, editor="float", unit="m")
    clearance: float = param(0.0, editor="float", unit="m")
    contact_height: float = param(0.08, editor="float", unit="m")
    slide_weight: float = param(1.0, editor="float")

    def check(self) -> None:
        if isinstance(self.joints, str):
            self.joints = tuple(j.strip() for j in self.joints.split(",") if j.strip())
        self.joints = tuple(self.joints)
        if not self.joints:
            raise UserError(f"constraint {self.kind!r}: field 'joints' lists no joint")
        for j in self.joints:
            joint_index(j, "joints", self.kind)

    def acts_on(self) -> tuple[str, ...]:
        return self.joints

    def _index(self) -> list[int]:
        return [joint_index(j, "joints", self.kind) for j in self.joints]

    def loss(self, state: PoseState) -> torch.Tensor:
        import torch
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
        return bool((z >= self.floor_height + self.clearance - _SLACK).all())

    def fast_term(self, frame: FrameInputs) -> "FloorTerm":
        return FloorTerm(self, frame.previous_positions)

    @classmethod
    def placement(cls, params: dict[str, Any], positions: np.ndarray) -> dict[str, Any]:
        """Nothing to place: the floor plane is under the body wherever it is."""
        return {}

    def gizmo(self, positions: np.ndarray | None = None) -> BoxGizmo | None:
        if self.floor_height == 0.0:
            return None  # the viewport already draws the z = 0 floor
        lo = np.array([-2.0, -2.0, self.floor_height - 0.005])
        hi = np.array([2.0, 2.0, self.floor_height])
        return BoxGizmo(lo, hi)


class FloorTerm:
    """The fast-path term of one :class:`FloorConstraint` for one frame (module doc)."""

    def __init__(self, c: FloorConstraint, previous: np.ndarray | None) -> None:
        self.name, self.weight, self.turns = c.name, c.weight, False
        self.idx = np.array(c._index(), dtype=np.intp)
        self.unique = len(set(self.idx.tolist())) == len(self.idx)
        self.low = c.floor_height + c.clearance
        self.ok = self.low - _SLACK
        self.prev = None
        if previous is not None and c.slide_weight > 0:
            prev = np.asarray(previous, dtype=np.float64)[self.idx]
            # as the reference compares in the previous pose's precision (float32)
            contact = prev[:, 2].astype(np.float32) < np.float32(c.floor_height + c.contact_height)
            self.prev, self.slide = prev[:, :2], c.slide_weight * contact.astype(np.float64)

    def evaluate(self, pos: np.ndarray, world: np.ndarray, g_pos: np.ndarray, g_rot: np.ndarray) -> float:
        p = pos[self.idx]
        g = np.zeros((len(self.idx), 3))
        under = np.maximum(self.low - p[:, 2], 0.0)
        out = float(under @ under)
        g[:, 2] = under
        g[:, 2] *= -2.0 * self.weight
        if self.prev is not None:
            d = p[:, :2] - self.prev
            out += float(self.slide @ (d * d).sum(-1))
            g[:, :2] = (2.0 * self.weight * self.slide)[:, None] * d
        if self.unique:
            g_pos[self.idx] += g
        else:  # a joint listed twice counts twice
            np.add.at(g_pos, self.idx, g)
        return out

    def satisfied(self, pos: np.ndarray, world: np.ndarray) -> bool:
        return bool((pos[self.idx, 2] >= self.ok).all())
