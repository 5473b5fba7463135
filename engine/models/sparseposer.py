"""SparsePoser's networks (Ponton et al. 2023, sec. 5.2), scaled to a 2-core CPU.

* **Generator**: a skeleton-aware convolutional autoencoder over a window of T frames.
  The dynamic encoder reads the root-space dual quaternions of the six tracked joints
  (placed on their nodes of the 22-joint graph, zeros elsewhere; slot 0 carries the
  root's rotation and displacement, the paper's D) and pools the skeleton 22 -> 14 -> 9
  -> 6 nodes with stride-2 skeletal convolutions; the decoder unpools and upsamples back
  to ``(T, 22, 8)`` root-space dual quaternions of the whole body. A static encoder turns
  the bone offsets into per-level features added after each decoder block.
* **Learned IK**: one small MLP per limb (two legs, two arms) that nudges the limb's
  four local rotations so its end joint (ankle / wrist) meets its tracker.

Skeletal convolutions reuse :class:`engine.models.skeletal.SkeletalLinear`: the K frames
of the temporal kernel are stacked as channels, so a node still reads only its graph
neighbours. All features are normalised with the ``data prepare`` statistics held as
buffers, so callers pass raw features.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import torch
from torch import nn
from torch.nn import functional as F

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
)

#: Tracked joints of preset ``6``, in the order of the sparse input.
SPARSE_JOINTS = ("root", "upperneck", "lwrist", "rwrist", "lankle", "rankle")
SPARSE_INDEX = tuple(sk.JOINT_INDEX[j] for j in SPARSE_JOINTS)
#: Limb chains the learned IK adjusts; the last joint of each is the tracked end effector.
LIMBS = (
    ("lhip", "lknee", "lankle", "ltoe"),
    ("rhip", "rknee", "rankle", "rtoe"),
    ("lclavicle", "lshoulder", "lelbow", "lwrist"),
    ("rclavicle", "rshoulder", "relbow", "rwrist"),
)
LIMB_INDEX = tuple(tuple(sk.JOINT_INDEX[j] for j in limb) for limb in LIMBS)
#: The tracked end effector of each limb (ankle for legs: the preset tracks the feet there).
LIMB_EE = tuple(sk.JOINT_INDEX[j] for j in ("lankle", "rankle", "lwrist", "rwrist"))
_PARENT_OR_SELF = [max(p, 0) for p in sk.PARENTS]


def local_rotations(g):
    """Local rotations ``(..., 22, 4)`` (slot 0 identity, w >= 0) from root-space joint
    rotations ``g (..., 22, 4)`` (raw real parts of the dual quaternions: normalised
    here; slot 0 is ignored). Numpy arrays or tensors."""
    g = Q.normalize(g)
    if isinstance(g, torch.Tensor):
        g = torch.cat((Q.identity(g.shape[:-2], like=g)[..., None, :], g[..., 1:, :]), dim=-2)
    else:
        g[..., 0, :] = Q.identity()
    parent = g[..., _PARENT_OR_SELF, :]
    return Q.canonicalize(Q.mul(Q.conjugate(parent), g))  # the root is its own parent: identity


@dataclass
class SparsePoserConfig(ModelConfig):
    """Architecture. ``channels[i]``: features per node after encoder block i."""

    window: int = 64
    channels: tuple[int, int, int] = (16, 32, 48)
    kernel: int = 3
    ik_hidden: int = 256
    neighbour_distance: int = 2
    negative_slope: float = 0.2


class SkeletalConv(nn.Module):
    """Temporal convolution over per-node features; node i reads only its neighbours.

    Input ``(B, T, N, C_in)``, output ``(B, T', N, C_out)`` with ``T' = ceil(T / stride)``
    (zero padding keeps the length at stride 1)."""

    def __init__(self, node_mask: np.ndarray, c_in: int, c_out: int, kernel: int, stride: int = 1):
        super().__init__()
        self.kernel, self.stride = kernel, stride
        self.linear = SkeletalLinear(node_mask, kernel * c_in, c_out)

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        b, t, n, c = x.shape
        pad = self.kernel // 2
        xp = F.pad(x, (0, 0, 0, 0, pad, pad))  # (B, T + 2 pad, N, C)
        win = xp.unfold(1, self.kernel, self.stride)  # (B, T', N, C, K)
        tt = win.shape[1]
        win = win.permute(0, 1, 2, 4, 3).reshape(b * tt, n, self.kernel * c)
        return self.linear(win).reshape(b, tt, n, -1)


def upsample2(x: torch.Tensor) -> torch.Tensor:
    """Linear temporal upsampling by two, ``(B, T, N, C) -> (B, 2T, N, C)``."""
    b, t, n, c = x.shape
    y = F.interpolate(x.permute(0, 2, 3, 1).reshape(b, n * c, t), scale_factor=2, mode="linear", align_corners=False)
    return y.reshape(b, n, c, 2 * t).permute(0, 3, 1, 2)


class SparsePoserGenerator(nn.Module):
    """Skeleton-aware convolutional autoencoder: sparse window -> full-body window."""

    # buffers (register_buffer in __init__), declared for the type checker
    pool0: torch.Tensor
    pool1: torch.Tensor
    pool2: torch.Tensor
    unpool0: torch.Tensor
    unpool1: torch.Tensor
    unpool2: torch.Tensor

    def __init__(self, cfg: SparsePoserConfig):
        super().__init__()
        self.cfg = cfg
        sizes = level_sizes()
        masks = [neighbour_mask(n, e, cfg.neighbour_distance) for n, e in zip(sizes, level_edges())]
        c0, c1, c2 = cfg.channels
        k = cfg.kernel
        self.act = nn.LeakyReLU(cfg.negative_slope)
        self.enc = nn.ModuleList(
            [
                SkeletalConv(masks[0], 8, c0, k, 2),
                SkeletalConv(masks[1], c0, c1, k, 2),
                SkeletalConv(masks[2], c1, c2, k, 2),
            ]
        )
        self.dec = nn.ModuleList(
            [SkeletalConv(masks[2], c2, c1, 3), SkeletalConv(masks[1], c1, c0, 3), SkeletalConv(masks[0], c0, c0, 3)]
        )
        self.out = SkeletalConv(masks[0], c0, 8, 3)
        self.static = nn.ModuleList(
            [SkeletalLinear(masks[0], 3, c0), SkeletalLinear(masks[1], c0, c0), SkeletalLinear(masks[2], c0, c1)]
        )
        for i, groups in enumerate(POOL_GROUPS):
            self.register_buffer(f"pool{i}", pool_matrix(groups, sizes[i]), persistent=False)
            self.register_buffer(f"unpool{i}", unpool_matrix(groups, sizes[i]), persistent=False)

    def static_features(self, offsets: torch.Tensor) -> list[torch.Tensor]:
        """Per-level features of the bone offsets ``(B, 22, 3)`` (metres): 22, 14, 9 nodes."""
        s0 = self.act(self.static[0](offsets * 10.0))
        s1 = self.act(self.static[1](torch.matmul(self.pool0, s0)))
        s2 = self.act(self.static[2](torch.matmul(self.pool1, s1)))
        return [s0, s1, s2]

    def forward(self, sparse: torch.Tensor, offsets: torch.Tensor, tail: int | None = None) -> torch.Tensor:
        """Full-body normalised dual quaternions ``(B, T, 22, 8)`` from the normalised
        sparse input ``(B, T, 22, 8)`` (zeros off the tracked nodes) and offsets ``(B, 22, 3)``.

        ``tail`` (realtime use) decodes only the last ``tail`` frames at every level; the
        last output frames then equal the full decode's (a test checks it) at a fraction
        of the cost."""
        pools = (self.pool0, self.pool1, self.pool2)
        x = sparse
        for conv, pool in zip(self.enc, pools):
            x = torch.matmul(pool, self.act(conv(x)))  # stride 2 in time, then pool nodes
        s0, s1, s2 = self.static_features(offsets)
        for conv, unpool, s in zip(self.dec, (self.unpool2, self.unpool1, self.unpool0), (s2, s1, s0)):
            x = upsample2(torch.matmul(unpool, x))
            if tail is not None:
                x = x[:, -tail:]
            x = self.act(conv(x)) + s[:, None]
        return self.out(x)


class LimbIK(nn.Module):
    """One limb's learned IK: generator pose of the limb + tracker -> adjusted local rotations."""

    def __init__(self, hidden: int):
        super().__init__()
        # limb joints' root-space dq (4 x 8), their offsets (4 x 3), the tracker's dq (8)
        last = nn.Linear(hidden, 16)
        self.net = nn.Sequential(
            nn.Linear(4 * 8 + 4 * 3 + 8, hidden), nn.LeakyReLU(0.2), nn.Linear(hidden, hidden), nn.LeakyReLU(0.2), last
        )
        nn.init.zeros_(last.weight)
        nn.init.zeros_(last.bias)

    def forward(self, limb_dq, limb_off, target_dq, limb_local):
        """Adjusted local rotations ``(B, 4, 4)`` of the limb (w >= 0)."""
        x = torch.cat((limb_dq.flatten(1), limb_off.flatten(1) * 10.0, target_dq), dim=-1)
        delta = self.net(x).reshape(-1, 4, 4)
        return Q.canonicalize(Q.normalize(limb_local + delta))


class SparsePoser(nn.Module):
    """Generator + learned IK, with the normalisation statistics as buffers."""

    # buffers (register_buffer in __init__), declared for the type checker
    dq_mean: torch.Tensor
    dq_std: torch.Tensor
    sparse_mask: torch.Tensor

    def __init__(self, config: SparsePoserConfig | None = None, stats: dict | None = None):
        super().__init__()
        self.config = cfg = config or SparsePoserConfig()
        if cfg.window % 8:
            raise ValueError(f"window must be a multiple of 8 (three stride-2 levels), got {cfg.window}")
        self.generator = SparsePoserGenerator(cfg)
        self.ik = nn.ModuleList([LimbIK(cfg.ik_hidden) for _ in LIMBS])
        self.register_buffer("dq_mean", torch.zeros(22, 8))
        self.register_buffer("dq_std", torch.ones(22, 8))
        sparse_mask = torch.zeros(22, 1)
        sparse_mask[list(SPARSE_INDEX)] = 1.0
        self.register_buffer("sparse_mask", sparse_mask, persistent=False)
        if stats is not None:
            for name in ("dq_mean", "dq_std"):
                getattr(self, name).copy_(torch.as_tensor(np.asarray(stats[name]), dtype=torch.float32))

    def normalise(self, dq: torch.Tensor) -> torch.Tensor:
        return (dq - self.dq_mean) / self.dq_std

    def sparse_input(self, dq: torch.Tensor) -> torch.Tensor:
        """Normalised sparse input ``(..., 22, 8)`` from raw root-space dq ``(..., 22, 8)``
        whose untracked joints may hold anything (they are zeroed)."""
        return self.normalise(dq) * self.sparse_mask

    def generate(self, dq: torch.Tensor, offsets: torch.Tensor, tail: int | None = None) -> torch.Tensor:
        """Generator output, normalised dq ``(B, T or tail, 22, 8)``, for raw dq windows
        ``(B, T, 22, 8)`` (only the tracked joints are read)."""
        return self.generator(self.sparse_input(dq), offsets, tail)

    def local_from_output(self, out: torch.Tensor) -> torch.Tensor:
        """Local rotations ``(..., 22, 4)`` (slot 0 identity: root space) from normalised dq."""
        raw = out * self.dq_std + self.dq_mean
        return local_rotations(raw[..., :4])

    def refine(
        self, gen_out: torch.Tensor, local: torch.Tensor, offsets: torch.Tensor, target_dq: torch.Tensor
    ) -> torch.Tensor:
        """Learned IK: local rotations ``(B, 22, 4)`` with each limb replaced by its network's.

        ``gen_out`` normalised dq ``(B, 22, 8)``, ``local`` its local rotations,
        ``offsets (B, 22, 3)``, ``target_dq`` raw root-space dq of the trackers ``(B, 22, 8)``
        (read at the end effectors)."""
        target = self.normalise(target_dq)
        parts = list(local.unbind(-2))
        for net, idx, ee in zip(self.ik, LIMB_INDEX, LIMB_EE):
            new = net(gen_out[:, idx], offsets[:, idx], target[:, ee], local[:, idx])
            for slot, j in enumerate(idx):
                parts[j] = new[:, slot]
        return torch.stack(parts, dim=-2)

    def forward(self, dq: torch.Tensor, offsets: torch.Tensor, tail: int | None = None):
        """Last-frame pose of each window: ``(local_ik, local_gen)``, each ``(B, 22, 4)``
        in root space (slot 0 identity)."""
        out = self.generate(dq, offsets, tail)[:, -1]
        local = self.local_from_output(out)
        return self.refine(out, local, offsets, dq[:, -1]), local
