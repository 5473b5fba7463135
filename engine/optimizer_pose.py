"""Decoded latent -> world pose, for the pose optimizer's inner loop.

Forward kinematics here processes the skeleton level by level (all joints at the same
depth at once: 7 levels instead of 21 joints) with rotation matrices, which keeps the
autograd graph, and the Python work per optimizer iteration, small (about 2.5x faster
than the per-joint quaternion FK with its backward pass). It matches
:func:`engine.kinematics.fk.fk` to float precision (tested).

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

from dataclasses import dataclass

import numpy as np
import torch

from engine import skeleton as sk
from engine.constraints.base import PoseState
from engine.kinematics import quaternion as Q
from engine.kinematics.fk import fk, fk_matrices
from engine.kinematics.root import integrate_root


class LevelFK:
    """The skeleton's offsets bound to :func:`engine.kinematics.fk.fk_matrices` (torch).

    Parameters
    ----------
    offsets : array (J, 3)
        Bone offsets, metres.
    parents : sequence of int
        Parent of every joint (root first, -1).
    """

    def __init__(self, offsets: np.ndarray, parents: tuple[int, ...] = sk.PARENTS,
                 dtype: torch.dtype = torch.float32) -> None:  # fmt: skip
        self.parents = tuple(parents)
        self.offsets = torch.as_tensor(np.asarray(offsets), dtype=dtype)

    def matrices(self, local_rot: torch.Tensor, root_pos: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor]:
        """World positions ``(..., J, 3)`` and rotation matrices ``(..., J, 3, 3)``.

        ``local_rot (..., J, 4)``: row 0 is the root's world rotation; ``root_pos (..., 3)``.
        """
        return fk_matrices(Q.to_matrix(local_rot), root_pos, self.offsets, self.parents)

    def quaternions(self, local_rot: torch.Tensor) -> torch.Tensor:
        """World rotations as quaternions ``(..., J, 4)`` (slower; computed on demand)."""
        return fk(local_rot, local_rot.new_zeros(local_rot.shape[:-2] + (3,)), self.offsets, self.parents)[1]


class DecodedPose(PoseState):
    """A :class:`PoseState` whose quaternion ``rotations`` are computed on first access.

    Most constraints need positions only, and rotation terms use ``rotation_matrices``,
    so the optimizer rarely pays for the quaternion chain.
    """

    def __init__(self, fk: LevelFK, positions: torch.Tensor, rotation_matrices: torch.Tensor,
                 local_rot: torch.Tensor, latent: torch.Tensor, previous_positions: torch.Tensor | None,
                 frame: int, prediction: torch.Tensor | None) -> None:  # fmt: skip
        self._fk = fk
        self.positions = positions
        self.rotation_matrices = rotation_matrices
        self.local_rot = local_rot
        self.latent = latent
        self.previous_positions = previous_positions
        self.frame = frame
        self.prediction = prediction

    def __getattr__(self, name: str):  # only called for attributes not set yet
        if name == "rotations":
            value = self._fk.quaternions(self.local_rot)
            self.__dict__["rotations"] = value
            return value
        raise AttributeError(name)


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
        """``positions (..., J, 3)`` shifted so row ``joint`` equals ``position``."""
        return positions + (self.position - positions[..., self.joint, :])[..., None, :]


def world_root(rot0: torch.Tensor, disp: torch.Tensor, prev: RootFrame,
               override: RootOverride | None = None) -> tuple[torch.Tensor, torch.Tensor]:  # fmt: skip
    """World root rotation ``(..., 4)`` and position ``(..., 3)`` (see the module doc).

    Parameters
    ----------
    rot0 : Tensor (..., 4)
        Decoded slot-0 rotation (root rotation in the previous heading frame).
    disp : Tensor (..., 3)
        Decoded root displacement in the previous heading frame, metres.
    prev : RootFrame
        The previous frame's solved root.
    override : RootOverride, optional
        Hip sensor reading that takes precedence.
    """
    rotation, position = integrate_root(prev.rotation.expand_as(rot0), prev.position, rot0, disp)
    if override is not None and override.rotation is not None:
        rotation = override.rotation.expand_as(rot0)
    if override is not None:
        position = override.position.expand_as(disp)
    return rotation, position
