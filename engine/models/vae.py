"""The pose VAE of DragPoser (Ponton et al. 2024, sec. 4.3).

Encoder: root-space dual quaternions ``(B, 22, 8)`` -> skeletal linear layers pooled
22 -> 14 -> 9 -> 6 nodes -> two linear heads for the mean and log-variance of a
24-d latent. Decoder: latent -> 6 nodes -> unpooled back to 22 -> one unit quaternion per
joint (the pose ``rot``: slot 0 the root rotation in the previous heading frame, the
others local rotations) and the root displacement (metres, previous heading frame).
Normalisation statistics live in the model as buffers, so callers pass raw features.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import torch
from torch import nn

from engine import skeleton as sk
from engine.kinematics import quaternion as Q
from engine.models.config import ModelConfig
from engine.models.skeletal import (
    POOL_GROUPS,
    SkeletalLinear,
    level_edges,
    level_sizes,
    neighbour_mask,
    pool_matrix,
    unpool_matrix,
    unpool_source,
)

#: Per pooling step, the coarse node each node of the finer level copies when unpooling.
UNPOOL_SOURCES = tuple(unpool_source(groups) for groups in POOL_GROUPS)


@dataclass
class VAEConfig(ModelConfig):
    """Architecture of the pose VAE. ``channels[i]`` = features per node at level i."""

    latent: int = 24
    channels: tuple[int, int, int, int] = (32, 48, 64, 96)
    neighbour_distance: int = 2
    negative_slope: float = 0.2


class PoseVAE(nn.Module):
    """Skeleton-aware variational autoencoder of single poses."""

    # buffers (register_buffer in __init__), declared for the type checker
    pool0: torch.Tensor
    pool1: torch.Tensor
    pool2: torch.Tensor
    unpool0: torch.Tensor
    unpool1: torch.Tensor
    unpool2: torch.Tensor
    dq_mean: torch.Tensor
    dq_std: torch.Tensor
    disp_mean: torch.Tensor
    disp_std: torch.Tensor

    def __init__(self, config: VAEConfig | None = None, stats: dict | None = None):
        super().__init__()
        self.config = cfg = config or VAEConfig()
        sizes = level_sizes()
        masks = [neighbour_mask(n, e, cfg.neighbour_distance) for n, e in zip(sizes, level_edges())]
        ch = cfg.channels
        act = lambda: nn.LeakyReLU(cfg.negative_slope)  # noqa: E731
        self.enc = nn.ModuleList(
            [
                SkeletalLinear(masks[0], 8, ch[0]),
                SkeletalLinear(masks[0], ch[0], ch[1]),
                SkeletalLinear(masks[1], ch[1], ch[2]),
                SkeletalLinear(masks[2], ch[2], ch[3]),
            ]
        )
        self.act = act()
        for i, groups in enumerate(POOL_GROUPS):
            self.register_buffer(f"pool{i}", pool_matrix(groups, sizes[i]))
            self.register_buffer(f"unpool{i}", unpool_matrix(groups, sizes[i]))
        flat = sizes[3] * ch[3]
        self.to_mu = nn.Linear(flat, cfg.latent)
        self.to_logvar = nn.Linear(flat, cfg.latent)
        self.from_latent = nn.Linear(cfg.latent, flat)
        self.dec = nn.ModuleList(
            [
                SkeletalLinear(masks[2], ch[3], ch[2]),
                SkeletalLinear(masks[1], ch[2], ch[1]),
                SkeletalLinear(masks[0], ch[1], ch[0]),
                SkeletalLinear(masks[0], ch[0], ch[0]),
            ]
        )
        self.to_rot = SkeletalLinear(masks[0], ch[0], 4)
        self.to_disp = nn.Linear(ch[0], 3)
        for name, shape in (("dq_mean", (22, 8)), ("dq_std", (22, 8)), ("disp_mean", (3,)), ("disp_std", (3,))):
            self.register_buffer(name, torch.zeros(shape) if "mean" in name else torch.ones(shape))
        if stats is not None:
            self.set_stats(stats)

    def set_stats(self, stats: dict) -> None:
        """Normalisation statistics from ``data prepare`` (``dq_mean``, ``dq_std``, ...)."""
        for name in ("dq_mean", "dq_std", "disp_mean", "disp_std"):
            getattr(self, name).copy_(torch.as_tensor(np.asarray(stats[name]), dtype=torch.float32))

    def encode(self, dq: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor]:
        """Mean and log-variance ``(B, L)`` of the latent for raw encoder input ``dq (B, 22, 8)``."""
        x = (dq - self.dq_mean) / self.dq_std
        x = self.act(self.enc[0](x))
        x = self.act(self.enc[1](x))
        x = torch.matmul(self.pool0, x)  # 22 -> 14
        x = self.act(self.enc[2](x))
        x = torch.matmul(self.pool1, x)  # 14 -> 9
        x = self.act(self.enc[3](x))
        x = torch.matmul(self.pool2, x)  # 9 -> 6
        flat = x.flatten(1)
        return self.to_mu(flat), self.to_logvar(flat)

    def decode(self, z: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor]:
        """Pose from latent ``z (B, L)``: unit quaternions ``(B, 22, 4)`` (w >= 0) and
        root displacement ``(B, 3)`` in metres."""
        x = self.act(self.from_latent(z)).reshape(z.shape[0], level_sizes()[3], self.config.channels[3])
        # each unpooling (6 -> 9 -> 14 -> 22 nodes) is read by the next layer in place
        x = self.act(self.dec[0](x, UNPOOL_SOURCES[2]))
        x = self.act(self.dec[1](x, UNPOOL_SOURCES[1]))
        x = self.act(self.dec[2](x, UNPOOL_SOURCES[0]))
        x = self.act(self.dec[3](x))
        q = self.to_rot(x) + torch.tensor([1.0, 0.0, 0.0, 0.0], device=z.device)  # identity-biased
        rot = Q.canonicalize(Q.normalize(q))
        disp = self.to_disp(x[:, 0]) * self.disp_std + self.disp_mean
        return rot, disp

    def forward(self, dq: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor, torch.Tensor, torch.Tensor]:
        """Encode, sample (reparameterisation), decode: ``rot, disp, mu, logvar``."""
        mu, logvar = self.encode(dq)
        z = mu + torch.randn_like(mu) * torch.exp(0.5 * logvar) if self.training else mu
        rot, disp = self.decode(z)
        return rot, disp, mu, logvar


def pose_distance(rot_a, disp_a, rot_b, disp_b, disp_std) -> torch.Tensor:
    """Mean squared difference of two poses (per batch element): quaternions compared
    sign-invariantly, displacement in units of its dataset standard deviation. ``(B,)``"""
    dot = (rot_a * rot_b).sum(-1, keepdim=True)
    rot_b = torch.where(dot < 0, -rot_b, rot_b)
    rq = ((rot_a - rot_b) ** 2).mean(dim=(-1, -2))
    rd = (((disp_a - disp_b) / disp_std) ** 2).mean(-1)
    return rq + rd / sk.NUM_JOINTS
