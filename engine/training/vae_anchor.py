"""The anchor term of a decoder fine-tune: away from the latents the encoder gives real
poses, keep decoding what a reference VAE (the shipped one) decodes.

Pose mode's drags step the latent freely and visit latents no real pose encodes to. A
decoder fine-tuned on the encoder's latents alone fits real poses better and draws those
other latents differently (assets/models/README.md, the fifth run: tracking improved, pose
authoring lost). The anchor samples latents around each pose's encoder latent, at a
per-sample distance drawn uniformly in ``[low, high]`` standard normal units, and asks the
trained decoder to match the frozen reference there, with the reconstruction loss's own
rotation and position weights.
"""

from __future__ import annotations

from pathlib import Path

import torch
from torch import nn

from engine.kinematics.features import root_space_fk
from engine.models.loading import load_vae
from engine.models.vae import PoseVAE, pose_distance


class DecoderAnchor(nn.Module):
    """``forward(vae, mu, offsets)``: the anchor loss for a batch of encoder means ``mu``."""

    def __init__(self, reference: PoseVAE, low: float, high: float, w_rot: float, w_fk: float):
        super().__init__()
        if not 0.0 <= low <= high:
            raise ValueError(f"anchor distances need 0 <= low <= high, got {low}, {high}")
        self.reference = reference.eval().requires_grad_(False)
        self.low, self.high, self.w_rot, self.w_fk = low, high, w_rot, w_fk

    @classmethod
    def from_file(cls, path: str | Path, low: float, high: float, w_rot: float, w_fk: float) -> DecoderAnchor:
        reference, _ = load_vae(Path(path))
        return cls(reference, low, high, w_rot, w_fk)

    def forward(self, vae: PoseVAE, mu: torch.Tensor, offsets: torch.Tensor) -> torch.Tensor:
        scale = self.low + (self.high - self.low) * torch.rand(mu.shape[0], 1, device=mu.device, dtype=mu.dtype)
        z = mu.detach() + scale * torch.randn_like(mu)
        with torch.no_grad():
            rot0, disp0 = self.reference.decode(z)
            pos0, _ = root_space_fk(rot0, offsets)
        rot, disp = vae.decode(z)
        pos, _ = root_space_fk(rot, offsets)
        l_rot = pose_distance(rot, disp, rot0, disp0, vae.disp_std).mean()
        return self.w_rot * l_rot + self.w_fk * ((pos - pos0) ** 2).mean()
