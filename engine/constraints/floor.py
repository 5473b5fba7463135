"""``floor``: feet stay above the floor and do not slide while in contact.

Two terms, summed over the listed joints (ankles and toes by default):

* **penetration**: ``relu(floor_height + clearance - z)^2`` (metres squared);
* **sliding**: ``slide_weight * |xy - xy_prev|^2`` for joints whose previous-frame
  height was below ``contact_height`` (a planted foot should not skate). The contact
  test uses the previous frame only, so it is a fixed mask within a solve.

Residual: ``relu(floor_height + clearance - z)`` per joint and ``sqrt(slide_weight) (xy -
xy_prev)`` per planted joint; a joint listed twice counts twice.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, ClassVar

import numpy as np

from engine.constraints.base import Constraint, joint_index, param
from engine.constraints.residual import FrameInputs, FrameRows, Kit, Residuals, Term
from engine.errors import UserError
from engine.gizmos import BoxGizmo

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

    def term(self, frame: FrameInputs) -> "FloorTerm":
        return FloorTerm(self, frame.previous_positions)

    @classmethod
    def examples(cls, positions: np.ndarray) -> list[Constraint]:
        return [
            cls(weight=4.0, clearance=0.2, floor_height=0.05, contact_height=0.4, slide_weight=2.0),
            cls(joints=("ltoe", "ltoe"), clearance=0.3),
        ]

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


class FloorTerm(FrameRows, Term):
    """``relu(low - z_k)`` per joint and, with a sliding weight, ``sqrt(slide_weight *
    contact_k) (xy_k - xy_prev_k)`` per joint, ``contact_k`` whether it touched the floor on
    the previous frame (module doc). The previous positions and the contact mask are
    fixed for the frame (``prev (A, k, 2)``, ``slide (A, k)``: per frame)."""

    PER_FRAME = ("prev", "slide")

    def __init__(self, c: FloorConstraint, previous: np.ndarray | None) -> None:
        self.names = (c.name,)
        self.idx = np.array(c._index(), dtype=np.intp)
        self.low = c.floor_height + c.clearance
        k = len(self.idx)
        self.sliding = c.slide_weight > 0
        self.prev, self.slide = np.zeros((1, k, 2)), np.zeros((1, k))
        if previous is not None and self.sliding:
            prev = np.asarray(previous, dtype=np.float64)[self.idx]
            # the previous pose arrives in float32; compare in its precision
            contact = prev[:, 2].astype(np.float32) < np.float32(c.floor_height + c.contact_height)
            self.prev[0], self.slide[0] = prev[:, :2], np.sqrt(c.slide_weight * contact.astype(np.float64))
        self.owner = np.zeros(3 * k if self.sliding else k, dtype=np.intp)
        self.entry_joint = np.r_[self.idx, np.repeat(self.idx, 2)] if self.sliding else self.idx
        self.check_group = np.r_[np.arange(k), np.full(len(self.owner) - k, -1)]  # each joint's depth, not sliding
        self.check_limit2 = np.full(k, _SLACK**2)

    def residual(self, kit: Kit, P: Any, W: Any, z: Any, jac: bool = False, rows: Any = None) -> Residuals:
        p, a, k = P[:, self.idx], P.shape[0], len(self.idx)
        under = kit.relu(self.low - p[:, :, 2])
        sel = self.select(P, rows)
        slide = self.slide[sel]
        if not self.sliding:
            r = under
        else:
            moved = (p[:, :, :2] - kit.const(self.prev[sel], P)) * kit.const(slide, P)[:, :, None]
            r = kit.cat([under, moved.reshape(a, 2 * k)], -1)
        if not jac:
            return Residuals(r)
        # every entry reads one joint: a per-entry block, whose sliding rows are constant
        # within the frame and whose depth rows are written at each evaluation
        d, depth = self.kept("d_pos", sel, lambda: self._position_jacobian(slide))
        np.multiply(under > 0.0, -1.0, out=depth)
        return Residuals(r, entry_joint=self.entry_joint, d_pos_entry=d)

    def _position_jacobian(self, slide: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The per-entry position block ``(A, m, 3)`` with its sliding rows (``slide`` along x
        and y, ``slide (A, k)``), and a view of its depth rows' z column ``(A, k)``."""
        k = len(self.idx)
        d = np.zeros((len(slide), len(self.owner), 3))
        if self.sliding:
            d[:, k:, :2] = np.repeat(slide, 2, axis=1)[:, :, None] * np.tile(np.eye(2), (k, 1))
        return d, d[:, :k, 2]
