"""The Rolling Prediction Model (Barquero et al. 2025, sec. 3), scaled to a 2-core CPU.

At frame t the network ``f`` reads the last ``I + 1`` tracking samples of head and hands
(position, 6D rotation, connected flag; a lost sample reads zeros) and the last ``M``
generated poses, and predicts the next ``W`` poses. The prediction-consistency anchor
function (PCAF) only lets it *correct* the previous prediction, by at most ``u_k`` per
step at horizon ``k``::

    P_t = P_{t-1} + U * tanh(f(X_t, C_t) - P_{t-1})

in normalised pose units. ``P_t[0]`` is the output pose; the window then rolls forward
(first pose out, a blank pose in), so a pose is refined over W steps, a little at a time
far ahead and more as it comes close. When a hand's tracking is lost the input simply
empties and the prediction runs on its own; when it returns, the correction is bounded,
so the pose re-enters smoothly.

**Features.** Everything is expressed in the heading frame of the current head tracker:
yaw-only rotation ``H_t`` of the head, origin under the head on the floor. A pose is
``(22, 3, 2)`` 6D rotations: slot 0 the root's rotation in that frame, the rest local
rotations. Where the body is comes from the head: the root is placed so that the
pose's head joint meets the head tracker (the paper: "the world trajectory is given by
the head position"). States (``P`` and the pose context) are kept in world form
(slot 0 a world rotation) and re-expressed in the current frame at every step.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import pymotion.rotations.ortho6d_torch as o6
import torch
from torch import nn

from engine import skeleton as sk
from engine.kinematics.fk import fk_matrices
from engine.models.config import ModelConfig

#: Tracked joints (preset ``3-head-hands``), in input order.
RPM_JOINTS = ("upperneck", "lwrist", "rwrist")
RPM_INDEX = tuple(sk.JOINT_INDEX[j] for j in RPM_JOINTS)
POSE_DIM = sk.NUM_JOINTS * 6
TRACK_DIM = len(RPM_JOINTS) * 10


@dataclass
class RPMConfig(ModelConfig):
    """Architecture: I + 1 tracking frames, M past poses, W predicted poses."""

    past_inputs: int = 10
    past_poses: int = 10
    window: int = 20
    hidden: int = 512
    blocks: int = 2


def uncertainty(window: int) -> torch.Tensor:
    """PCAF's ``U`` (RPM supp. Eq. B): ``u(tau) = 1 - cos((tau + 1) / W * pi / 2)`` at
    distance ``tau`` frames from the present: small for the pose about to be output
    (0.003 for W = 20), 1 for the farthest, so a pose takes its big changes while it is
    far in the future and only small corrections near the present."""
    k = torch.arange(window, dtype=torch.float32)
    return 1.0 - torch.cos(0.5 * math.pi * (k + 1.0) / window)


class _Block(nn.Module):
    def __init__(self, h: int):
        super().__init__()
        self.net = nn.Sequential(nn.LayerNorm(h), nn.Linear(h, h), nn.GELU(), nn.Linear(h, h))

    def forward(self, x):
        return x + self.net(x)


class RPM(nn.Module):
    """``f``: tracking window + pose context -> W poses (normalised), and PCAF."""

    # buffers (register_buffer in __init__), declared for the type checker
    pose_mean: torch.Tensor
    pose_std: torch.Tensor
    track_mean: torch.Tensor
    track_std: torch.Tensor
    u: torch.Tensor

    def __init__(self, config: RPMConfig | None = None, stats: dict | None = None):
        super().__init__()
        self.config = cfg = config or RPMConfig()
        n_in = (cfg.past_inputs + 1) * TRACK_DIM + cfg.past_poses * POSE_DIM
        self.net = nn.Sequential(
            nn.Linear(n_in, cfg.hidden),
            nn.GELU(),
            *[_Block(cfg.hidden) for _ in range(cfg.blocks)],
            nn.LayerNorm(cfg.hidden),
            nn.Linear(cfg.hidden, cfg.window * POSE_DIM),
        )
        self.register_buffer("pose_mean", torch.zeros(POSE_DIM))
        self.register_buffer("pose_std", torch.ones(POSE_DIM))
        self.register_buffer("track_mean", torch.zeros(TRACK_DIM))
        self.register_buffer("track_std", torch.ones(TRACK_DIM))
        # structure, rebuilt from the config (some weights files hold an inverted U; it is ignored)
        self.register_buffer("u", uncertainty(cfg.window), persistent=False)
        if stats is not None:
            for k, v in stats.items():
                getattr(self, k).copy_(torch.as_tensor(np.asarray(v), dtype=torch.float32))

    def _load_from_state_dict(self, state_dict, prefix, *args, **kwargs):
        state_dict.pop(prefix + "u", None)
        super()._load_from_state_dict(state_dict, prefix, *args, **kwargs)

    def norm_pose(self, pose6: torch.Tensor) -> torch.Tensor:
        """``(..., 22, 3, 2)`` canonical poses -> ``(..., 132)`` normalised."""
        return (pose6.flatten(-3) - self.pose_mean) / self.pose_std

    def denorm_pose(self, x: torch.Tensor) -> torch.Tensor:
        return (x * self.pose_std + self.pose_mean).unflatten(-1, (sk.NUM_JOINTS, 3, 2))

    def forward(self, track: torch.Tensor, context: torch.Tensor) -> torch.Tensor:
        """``f``: raw tracking features ``(B, I+1, 30)`` and canonical pose context
        ``(B, M, 22, 3, 2)`` -> normalised predictions ``(B, W, 132)``."""
        tr = (track - self.track_mean) / self.track_std
        flags = track[..., 9::10]  # a lost sample stays all zeros after normalising
        tr = tr * flags.repeat_interleave(10, dim=-1)
        x = torch.cat((tr.flatten(1), self.norm_pose(context).flatten(1)), dim=-1)
        return self.net(x).unflatten(-1, (self.config.window, POSE_DIM))

    def pcaf(self, prev: torch.Tensor, f: torch.Tensor) -> torch.Tensor:
        """``P_t = P_{t-1} + U * tanh(f - P_{t-1})``, both ``(B, W, 132)`` normalised."""
        return prev + self.u[:, None] * torch.tanh(f - prev)


def yaw_matrix(head_rot: torch.Tensor) -> torch.Tensor:
    """Yaw-only rotation matrices ``(..., 3, 3)`` of the head's heading (Z up, faces -Y)."""
    m = o6.quat.to_matrix(head_rot)
    fwd = -m[..., :, 1]  # the head's forward (-Y) in world
    yaw = torch.atan2(fwd[..., 0], -fwd[..., 1])
    c, s = torch.cos(yaw), torch.sin(yaw)
    z, o = torch.zeros_like(c), torch.ones_like(c)
    return torch.stack((torch.stack((c, -s, z), -1), torch.stack((s, c, z), -1), torch.stack((z, z, o), -1)), -2)


def to_frame(pose6: torch.Tensor, h: torch.Tensor, inverse: bool = True) -> torch.Tensor:
    """Re-express slot 0 (root rotation) of poses ``(B, K, 22, 3, 2)`` in the heading
    frame ``h (B, 3, 3)`` (``inverse=False``: back to world)."""
    hh = h.transpose(-1, -2) if inverse else h
    root = torch.matmul(hh[:, None], pose6[:, :, 0])
    return torch.cat((root[:, :, None], pose6[:, :, 1:]), dim=2)


def track_features(
    pos: torch.Tensor, rot6: torch.Tensor, flags: torch.Tensor, h: torch.Tensor, origin: torch.Tensor
) -> torch.Tensor:
    """Tracking features ``(B, K, 30)`` in the heading frame ``h (B, 3, 3)`` at ``origin (B, 3)``.

    ``pos (B, K, 3, 3)`` world positions, ``rot6 (B, K, 3, 3, 2)`` world 6D rotations,
    ``flags (B, K, 3)`` connected; lost samples become zeros (flag 0)."""
    hinv = h.transpose(-1, -2)[:, None, None]
    p = torch.matmul(hinv, (pos - origin[:, None, None])[..., None])[..., 0]
    r = torch.matmul(hinv, rot6).flatten(-2)
    f = flags.to(p.dtype)[..., None]
    return (torch.cat((p, r, torch.ones_like(f)), dim=-1) * f).flatten(-2)


def fk_root_space(pose6: torch.Tensor, offsets: torch.Tensor) -> torch.Tensor:
    """Joint positions ``(..., 22, 3)`` of poses ``(..., 22, 3, 2)`` with the root at
    the origin (slot 0's rotation applied); ``offsets (..., 22, 3)`` metres. The
    skeleton's one FK pass (:func:`engine.kinematics.fk.fk_matrices`)."""
    origin = torch.zeros(pose6.shape[:-3] + (3,), dtype=pose6.dtype, device=pose6.device)
    return fk_matrices(o6.to_matrix(pose6), origin, offsets)[0]


def rolling_step(
    model: RPM, P: torch.Tensor, context: torch.Tensor, track: torch.Tensor, h: torch.Tensor
) -> torch.Tensor:
    """One RPM step, batched: the new prediction ``P (B, W, 22, 3, 2)`` in world form.

    ``P`` is the previous prediction (world form, already rolled: its first pose is the
    one for this frame), ``context (B, M, 22, 3, 2)`` the past generated poses (world
    form), ``track (B, I+1, 30)`` the tracking features (built in frame ``h``)."""
    prev = model.norm_pose(to_frame(P, h))
    f = model(track, to_frame(context, h))
    new = model.pcaf(prev, f)
    return to_frame(model.denorm_pose(new), h, inverse=False)


def roll(P: torch.Tensor, context: torch.Tensor, blank: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor]:
    """Move one frame forward: ``P[0]`` joins the context (oldest pose out) and ``blank
    (B, 22, 3, 2)`` (world form) is appended to ``P``."""
    context = torch.cat((context[:, 1:], P[:, :1]), dim=1)
    return torch.cat((P[:, 1:], blank[:, None]), dim=1), context


def blank_pose(model: RPM, h: torch.Tensor) -> torch.Tensor:
    """The normalised-zero (mean) pose in world form for heading ``h (B, 3, 3)``: ``(B, 22, 3, 2)``."""
    mean = model.denorm_pose(torch.zeros(h.shape[0], 1, POSE_DIM, dtype=h.dtype))
    return to_frame(mean, h, inverse=False)[:, 0]
