"""Decoded latent -> world pose: the root rules and the reference (autograd) decode.

Forward kinematics is :func:`engine.kinematics.fk.fk_matrices` (level-ordered, rotation
matrices, so rotation losses need no quaternion chain).

Root handling (see ``docs/optimizer.md``):

* **hip sensor connected**: the root's world position is the sensor's; its world
  rotation is the sensor's for a 6-DoF tracker (DragPoser's joint adjustment). A 3-DoF
  hip keeps the decoded rotation, integrated as below.
* **otherwise** the root rotation is integrated from the decoded pose: slot 0 of ``rot``
  is the root rotation in the previous frame's heading frame ``H``, so ``R = H * rot[0]``.
  The root position is

  - **anchored to the head** (:class:`RootAnchor`, the default when a head tracker is
    connected): the whole body is translated so the decoded head lands on the head
    tracker, ``p = head_target - (FK_head(R, rot) - p)``. The decoded torso decides how
    far below the head the hips are; nothing accumulates from frame to frame.
  - **integrated** otherwise: ``p = p_prev + H * disp`` with ``disp`` the decoded
    displacement in ``H``. The gradients of every constraint then reach the root through
    the decoder, and errors accumulate (drift) when no tracker pins the body.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Protocol, runtime_checkable

import numpy as np
import torch

from engine.kinematics import quat_np as QN
from engine.kinematics import quaternion as Q
from engine.kinematics.root import anchor_body


@dataclass
class RootFrame:
    """The previous frame's solved root, the reference the decoded root is relative to.

    Attributes
    ----------
    rotation : Tensor (4,)
        World root rotation of the previous frame.
    position : Tensor (3,)
        World root position of the previous frame, metres.
    """

    rotation: torch.Tensor
    position: torch.Tensor

    def heading(self) -> torch.Tensor:
        """Yaw-only part ``H`` of the previous root rotation, ``(4,)``."""
        return Q.heading(self.rotation)


@dataclass
class RootOverride:
    """Root pose dictated by a connected hip sensor (``rotation`` None for 3-DoF)."""

    position: torch.Tensor
    rotation: torch.Tensor | None = None


@runtime_checkable
class BodyAnchor(Protocol):
    """What places a decoded body without a hip tracker (:attr:`FrameContext.root_anchor
    <engine.solver.frame.FrameContext>`): the autograd decode shifts the positions by
    :meth:`apply`. :class:`RootAnchor` pins a joint; the authoring's ``Ground`` stands
    the lowest foot on the floor."""

    def apply(self, positions: torch.Tensor) -> torch.Tensor:
        """``positions (..., J, 3)`` metres, shifted as the anchor places the body."""
        ...


@runtime_checkable
class JointAnchor(BodyAnchor, Protocol):
    """A :class:`BodyAnchor` that places the body by one joint, which is all the fast
    objective's chain knows (:func:`engine.solver.optimizer._root_frames` reads these two)."""

    joint: int  # joint index
    position: torch.Tensor  # (3,) the joint's world target, metres


@dataclass
class RootAnchor:
    """Without a hip tracker: translate the body so ``joint`` sits at ``position``.

    Attributes
    ----------
    joint : int
        Joint index (the head, ``upperneck``, for DragPoser's trackers).
    position : Tensor (3,)
        World target of that joint, metres.
    """

    joint: int
    position: torch.Tensor

    def apply(self, positions: torch.Tensor) -> torch.Tensor:
        """``positions (..., J, 3)`` shifted so row ``joint`` equals ``position`` (an
        anchor's hook: the authoring's ``Ground`` places a pose by other rules)."""
        return anchor_body(positions, self.joint, self.position)


#: ``heading = anchor``: the reference heading stays within this many degrees of the
#: anchor (head) tracker's heading. A head turns about 60-80 degrees against the hips at
#: most; a reference beyond that is drift, or the start of a flip, and is pulled back.
HEADING_LIMIT_DEG = 60.0
#: Below this horizontal length of the tracker's forward axis (looking almost straight
#: up or down) its heading is undefined and no limit is applied.
_MIN_FORWARD = 0.3


def _yaw(q: np.ndarray) -> float:
    """Angle (radians) about +Z of the horizontal projection of ``q``'s forward (-Y) axis,
    0 for the rest forward."""
    fw = QN.rotate(q, np.array([0.0, -1.0, 0.0]))
    return math.atan2(fw[0], -fw[1])


def _target_yaw(q: np.ndarray) -> float | None:
    """:func:`_yaw` of a rotation to go by, None when its forward axis is nearly vertical
    (a tracker looking straight up or down has no heading)."""
    fw = QN.rotate(q, np.array([0.0, -1.0, 0.0]))
    return None if math.hypot(fw[0], fw[1]) < _MIN_FORWARD else math.atan2(fw[0], -fw[1])


def _turned(q: np.ndarray, angle: float) -> np.ndarray:
    """``q (4,)`` turned about the world +Z by ``angle`` radians."""
    return QN.mul(np.array([math.cos(angle / 2), 0.0, 0.0, math.sin(angle / 2)]), q)


def clamp_heading(
    previous: np.ndarray, anchor_rotation: np.ndarray, limit_deg: float = HEADING_LIMIT_DEG
) -> np.ndarray:
    """The previous root rotation ``(4,)`` turned about +Z just enough that its heading
    is within ``limit_deg`` of the heading of ``anchor_rotation (4,)`` (both world,
    (w, x, y, z)); unchanged when it already is, or when the anchor's forward axis is
    nearly vertical."""
    yaw_anchor = _target_yaw(anchor_rotation)
    if yaw_anchor is None:
        return previous
    diff = math.remainder(_yaw(previous) - yaw_anchor, 2 * math.pi)
    limit = math.radians(limit_deg)
    if abs(diff) <= limit:
        return previous
    return _turned(previous, math.copysign(limit, diff) - diff)  # onto the limit


def follow_heading(previous: np.ndarray, target: np.ndarray, fraction: float) -> np.ndarray:
    """The root rotation ``previous (4,)`` turned about +Z by ``fraction`` (0-1) of the
    angle between its heading and that of ``target (4,)`` (both world, (w, x, y, z)):
    a first-order follow, one frame's share of a time constant (:func:`follow_fraction`);
    unchanged when ``target``'s forward axis is nearly vertical."""
    yaw_target = _target_yaw(target)
    if yaw_target is None or fraction <= 0.0:
        return previous
    diff = math.remainder(_yaw(previous) - yaw_target, 2 * math.pi)
    return _turned(previous, -fraction * diff)


def follow_fraction(time_constant_s: float, fps: float) -> float:
    """One frame's share ``1 - exp(-1 / (fps tau))`` of a first-order follow with time
    constant ``tau`` seconds (0 for ``tau`` 0: no follow)."""
    return 0.0 if time_constant_s <= 0.0 else 1.0 - math.exp(-1.0 / (fps * time_constant_s))


#: Left/right tracker pairs that say which way the body faces, with their weights. Feet
#: and hands alike: on the 50 validation files (150 frames each) the facing read this way is
#: 18 degrees from the truth's pelvis heading on average against 29 with the hands at
#: half weight (``research/heading_3dof.py``; docs/optimizer.md, "Heading without a hip
#: tracker"). The IK baseline reads its heading the same way.
LATERAL_PAIRS = (("lankle", "rankle", 1.0), ("lwrist", "rwrist", 1.0))
#: ``heading = anchor`` with a hip tracker that gives no rotation: the reference heading
#: stays within this many degrees of the body heading read off the tracker pairs. That
#: heading is a rough one (the line between the feet swings with each stride; 8-45 deg
#: mean error on the validation clips), so it only bounds the drift of the integrated
#: heading; the solver places the pelvis within the bound.
BODY_HEADING_LIMIT_DEG = 45.0


def body_facing(points: dict[str, np.ndarray], pairs=LATERAL_PAIRS, min_length: float = 1e-6) -> np.ndarray | None:
    """Heading rotation ``(4,)`` (about +Z) of a body whose tracked joints are at
    ``points`` (joint name -> world position ``(3,)``, metres): the canonical body (left
    = +X, forward = -Y) turned so its left-right axis lies along the weighted sum of the
    horizontal left-minus-right vectors of ``pairs`` (left, right, weight). None without
    a pair or when that sum is shorter than ``min_length`` metres."""
    lateral, found = np.zeros(2), False
    for left, right, w in pairs:
        if left in points and right in points:
            lateral += w * (np.asarray(points[left])[:2] - np.asarray(points[right])[:2])
            found = True
    if not found or math.hypot(*lateral) <= min_length:
        return None
    return _facing_left(lateral)


def _facing_left(lateral: np.ndarray) -> np.ndarray:
    """Heading rotation ``(4,)`` (about +Z) that turns the canonical left (+X) onto the
    horizontal vector ``lateral (2,)``."""
    yaw = math.atan2(lateral[1], lateral[0])
    return np.array([math.cos(yaw / 2), 0.0, 0.0, math.sin(yaw / 2)])


#: :func:`head_hands_facing`: the head's facing counts as much as the line between two
#: hands this many metres apart (about shoulder width: hands held close together say
#: little about the body's heading, hands spread wide say a lot).
HEAD_LATERAL_M = 0.5


def head_hands_facing(
    head_rotation: np.ndarray, points: dict[str, np.ndarray], head_lateral_m: float = HEAD_LATERAL_M
) -> np.ndarray | None:
    """Heading rotation ``(4,)`` (about +Z) of the body from a head tracker's world
    rotation ``head_rotation (4,)`` and the hands' positions in ``points`` (joint name ->
    world position ``(3,)``, metres; ``lwrist`` and ``rwrist``): the sum of the hands'
    horizontal left-minus-right vector and the head's horizontal left axis scaled to
    ``head_lateral_m`` metres, as in :func:`body_facing`. The head alone when a hand is
    missing; None when the sum vanishes (head looking straight up or down, no hands)."""
    left = QN.rotate(np.asarray(head_rotation, dtype=np.float64), np.array([1.0, 0.0, 0.0]))
    fw = QN.rotate(np.asarray(head_rotation, dtype=np.float64), np.array([0.0, -1.0, 0.0]))
    # the head's facing from its forward axis (the head rolls less than it pitches), as a left vector
    flat = np.array([-fw[1], fw[0]])
    n = math.hypot(*flat)
    if n < _MIN_FORWARD:  # looking up or down: its left axis still says which way it faces
        flat, n = left[:2], math.hypot(*left[:2])
    lateral = head_lateral_m * flat / n if n > 1e-9 else np.zeros(2)
    if "lwrist" in points and "rwrist" in points:
        lateral = lateral + (np.asarray(points["lwrist"])[:2] - np.asarray(points["rwrist"])[:2])
    if math.hypot(*lateral) <= 1e-6:
        return None
    return _facing_left(lateral)
