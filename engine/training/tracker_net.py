"""Training the tracker networks (:mod:`engine.solver.tracker_net`) on prepared shards.

A sample is a frame of a training take (mirrored shards included): the input is
:func:`~engine.solver.tracker_net.window_features` of the bank joints' simulated readings
(their world poses from forward kinematics) over the window ending at the frame, padded
with the take's first frame before its start as a live window is; the target is the VAE
encoder's mean latent of the frame's true pose. A perceptron with two hidden layers is
fitted per combination with a mean squared error, AdamW and a cosine learning rate.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from engine import skeleton as sk
from engine.errors import UserError
from engine.solver.tracker_net import WINDOW, TrackerNet, window_features
from engine.solver.tracker_prior import BANK_JOINTS


@dataclass(frozen=True)
class Takes:
    """Every take of a split: bank joints' world positions ``(F, 6, 3)`` and rotations
    ``(F, 6, 4)`` (:data:`BANK_JOINTS` order) and the encoder's latents ``(F, L)``."""

    positions: list[np.ndarray]
    rotations: list[np.ndarray]
    latents: list[np.ndarray]


def load_takes(data: Path, split: str, vae) -> Takes:
    """The takes of ``split`` in a prepared folder, encoded by ``vae`` (a ``PoseVAE``)."""
    import torch

    from engine.kinematics.features import encoder_input, pose_from_motion
    from engine.kinematics.fk import fk
    from engine.training.data import read_manifest
    from engine.training.predictor import encode_all

    manifest = read_manifest(data)
    cols = [sk.JOINT_INDEX[j] for j in BANK_JOINTS]
    out = Takes([], [], [])
    for e in manifest["files"]:
        if e["split"] != split:
            continue
        with np.load(data / e["shard"]) as z:
            local, root, offsets = z["local_rot"], z["root_pos"], z["offsets"]
        p, r = fk(local, root, offsets)
        rot, disp = pose_from_motion(
            torch.as_tensor(local, dtype=torch.float64), torch.as_tensor(root, dtype=torch.float64)
        )
        offs = torch.as_tensor(offsets, dtype=torch.float64).expand(rot.shape[0], -1, -1)
        out.positions.append(p[:, cols])
        out.rotations.append(r[:, cols])
        out.latents.append(encode_all(vae, encoder_input(rot, disp, offs).float()).numpy())
    if not out.latents:
        raise UserError(f"{data}: no '{split}' shards in manifest.json")
    return out


def samples(takes: Takes, joints: Sequence[str], stride: int = 1) -> tuple[np.ndarray, np.ndarray]:
    """Inputs ``(N, D)`` and target latents ``(N, L)`` of every ``stride``-th frame of each take."""
    cols = [BANK_JOINTS.index(j) for j in joints]
    xs, zs = [], []
    for pos, rot, lat in zip(takes.positions, takes.rotations, takes.latents, strict=True):
        t = np.arange(0, len(pos), stride)
        for chunk in np.array_split(t, max(1, len(t) // 512)):
            idx = np.maximum(chunk[:, None] - (WINDOW - 1) + np.arange(WINDOW)[None], 0)
            xs.append(window_features(pos[idx][:, :, cols], rot[idx][:, :, cols], joints).astype(np.float32))
        zs.append(lat[t])
    return np.concatenate(xs), np.concatenate(zs)


def train_net(
    joints: Sequence[str],
    x: np.ndarray,
    z: np.ndarray,
    hidden: int = 512,
    epochs: int = 20,
    lr: float = 1e-3,
    seed: int = 0,
    progress=None,
    decoder=None,
    pose_weight: float = 0.0,
) -> TrackerNet:
    """Fit one combination's network (two hidden layers of ``hidden``, ReLU, dropout 0.1)
    to latents ``z (N, L)`` from inputs ``x (N, D)``; ``progress(epoch, mse)`` after each epoch.
    With a ``decoder`` (the VAE, frozen) and ``pose_weight`` > 0 the loss adds the decoded
    poses' difference: per joint ``1 - cos^2`` of the half angle between the rotations the
    guessed and the true latent decode to, so latent directions that turn joints more weigh
    more."""
    import torch

    torch.manual_seed(seed)
    mean, std = x.mean(0).astype(np.float64), x.std(0).astype(np.float64) + 1e-6
    xt = torch.as_tensor(((x - mean) / std).astype(np.float32))
    zt = torch.as_tensor(z, dtype=torch.float32)
    net = torch.nn.Sequential(
        torch.nn.Linear(x.shape[1], hidden),
        torch.nn.ReLU(),
        torch.nn.Dropout(0.1),
        torch.nn.Linear(hidden, hidden),
        torch.nn.ReLU(),
        torch.nn.Dropout(0.1),
        torch.nn.Linear(hidden, z.shape[1]),
    )
    opt = torch.optim.AdamW(net.parameters(), lr=lr, weight_decay=1e-4)
    sched = torch.optim.lr_scheduler.CosineAnnealingLR(opt, epochs)
    gen = torch.Generator().manual_seed(seed)
    for epoch in range(epochs):
        net.train()
        total = 0.0
        for b in torch.randperm(len(xt), generator=gen).split(1024):
            guess = net(xt[b])
            loss = torch.nn.functional.mse_loss(guess, zt[b])
            if decoder is not None and pose_weight > 0:
                with torch.no_grad():
                    true_rot = decoder.decode(zt[b])[0]
                dot = (decoder.decode(guess)[0] * true_rot).sum(-1)
                loss = loss + pose_weight * (1.0 - dot * dot).mean()
            opt.zero_grad()
            loss.backward()
            opt.step()
            total += float(loss.detach()) * len(b)
        sched.step()
        if progress is not None:
            progress(epoch + 1, total / len(xt))
    layers = [m for m in net if isinstance(m, torch.nn.Linear)]
    return TrackerNet(
        tuple(joints),
        mean,
        std,
        tuple(m.weight.detach().numpy().T.copy() for m in layers),
        tuple(m.bias.detach().numpy().copy() for m in layers),
    )


def latent_mse(net: TrackerNet, x: np.ndarray, z: np.ndarray) -> float:
    """Mean squared error of the network's latents on samples ``x``, ``z``."""
    return float(np.mean((net.forward(x) - z) ** 2))
