"""The decoded pose every constraint judges (torch, differentiable w.r.t. the latent)."""

from __future__ import annotations

from dataclasses import dataclass

import torch

from engine.kinematics.fk import fk


@dataclass
class PoseState:
    """A pose in world space plus what constraints may compare it with.

    Attributes
    ----------
    positions : Tensor (22, 3)
        World joint positions, metres (Z-up, floor at z = 0).
    rotations : Tensor (22, 4) or None
        World joint rotations (w, x, y, z), when the producer computed them; use
        :meth:`world_rotations` to get them either way.
    local_rot : Tensor (22, 4)
        Local joint rotations; row 0 is the root's world rotation.
    latent : Tensor (L,)
        The latent vector being optimised.
    previous_positions : Tensor (22, 3) or None
        The previous frame's solved positions (for pins and foot contact).
    frame : int
        Frame index in the clip.
    prediction : Tensor (L,) or None
        The temporal predictor's latent for this frame, if it has one.
    rotation_matrices : Tensor (22, 3, 3) or None
        World rotations as matrices, when the producer has them (the solver does).
    """

    positions: torch.Tensor
    rotations: torch.Tensor | None
    local_rot: torch.Tensor
    latent: torch.Tensor
    previous_positions: torch.Tensor | None = None
    frame: int = 0
    prediction: torch.Tensor | None = None
    rotation_matrices: torch.Tensor | None = None

    def world_rotations(self) -> torch.Tensor:
        """World joint rotations ``(22, 4)``: :attr:`rotations`, or the quaternion chain of
        :attr:`local_rot` (bone offsets do not affect rotations)."""
        if self.rotations is not None:
            return self.rotations
        zero = self.local_rot.new_zeros(self.local_rot.shape[:-1] + (3,))
        return fk(self.local_rot, zero[..., 0, :], zero)[1]

    def detached(self) -> "PoseState":
        """A copy without autograd history (same tensors' values)."""
        d = lambda t: t.detach() if isinstance(t, torch.Tensor) else t  # noqa: E731
        return PoseState(
            d(self.positions),
            d(self.rotations),
            d(self.local_rot),
            d(self.latent),
            d(self.previous_positions),
            self.frame,
            d(self.prediction),
            d(self.rotation_matrices),
        )
