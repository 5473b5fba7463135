"""Training the heading network (:mod:`engine.models.heading`) on prepared shards.

Every ``stride``-th frame of a take is a sample: the six trackers' positions over the last
half second (the take's first frame repeated before its start, as a live window starts), and
the angle from their rough facing to the true pelvis heading. Mirrored shards give the
left-right swapped samples.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from engine import skeleton as sk
from engine.models.heading import JOINTS, HeadingModel, heading_features, window_frames
from engine.training.data import shard_motions
from engine.training.perceptron import fit_perceptron

_IDX = [sk.JOINT_INDEX[j] for j in JOINTS]


@dataclass(frozen=True)
class HeadingSamples:
    """Features ``(N, N_FEATURES)`` (float32), the rough facing's angle ``(N,)`` and the
    true pelvis heading's angle ``(N,)`` (radians about +Z)."""

    x: np.ndarray
    rough: np.ndarray
    truth: np.ndarray

    @property
    def target(self) -> np.ndarray:
        """The angle from the rough facing to the truth, wrapped to (-pi, pi]."""
        return np.angle(np.exp(1j * (self.truth - self.rough)))


def pelvis_yaw(root_rot: np.ndarray) -> np.ndarray:
    """Heading angle (radians about +Z, 0 facing -Y) of world root rotations ``(F, 4)``
    (w, x, y, z): where the pelvis's forward axis points on the floor."""
    w, x, y, z = np.moveaxis(np.asarray(root_rot, dtype=np.float64), -1, 0)
    # the rotated -Y axis: -(2(xy - wz), 1 - 2(x^2 + z^2))
    fx, fy = -2.0 * (x * y - w * z), -(1.0 - 2.0 * (x * x + z * z))
    return np.arctan2(fx, -fy)


def clip_samples(pos: np.ndarray, root_rot: np.ndarray, fps: float, stride: int = 1) -> HeadingSamples:
    """Samples of one clip: joint positions ``(F, 22, 3)`` (metres, z up) and world root
    rotations ``(F, 4)``."""
    k = window_frames(fps)
    tracked = pos[:, _IDX]
    padded = np.concatenate([np.repeat(tracked[:1], k - 1, axis=0), tracked])
    frames = np.arange(0, len(pos), stride)
    windows = np.lib.stride_tricks.sliding_window_view(padded, k, axis=0)[frames]  # (N, 6, 3, K)
    x, rough = heading_features(windows.transpose(0, 3, 1, 2))
    return HeadingSamples(x.astype(np.float32), rough, pelvis_yaw(root_rot[frames]))


def load_samples(data: Path, split: str, stride: int = 1, mirrored: bool = True) -> HeadingSamples:
    """Samples of every shard of ``split`` in a prepared folder (its ``manifest.json``)."""
    parts = [
        clip_samples(m.positions, np.asarray(m.local_rot[:, 0], dtype=np.float64), m.fps, stride)
        for m in shard_motions(data, split, mirrored)
    ]
    return HeadingSamples(*(np.concatenate([getattr(p, f) for p in parts]) for f in ("x", "rough", "truth")))


def train_heading(
    train: HeadingSamples, hidden: int = 256, epochs: int = 10, lr: float = 2e-3, seed: int = 0
) -> HeadingModel:
    """Fit the perceptron (two hidden layers of ``hidden``) to the unit vector of the
    correction angle (mean squared error), Adam with a cosine-annealed rate."""
    import torch

    t = train.target
    y = np.stack([np.cos(t), np.sin(t)], axis=-1)
    return HeadingModel(
        *fit_perceptron(train.x, y, torch.nn.functional.mse_loss, hidden, epochs, lr, seed, cosine=True)
    )


def angle_error_deg(model: HeadingModel | None, s: HeadingSamples) -> np.ndarray:
    """Per sample, degrees between the true pelvis heading and the model's (the rough
    facing's when ``model`` is None)."""
    est = s.rough if model is None else s.rough + model.correction(s.x)
    return np.degrees(np.abs(np.angle(np.exp(1j * (est - s.truth)))))
