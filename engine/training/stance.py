"""Training the stance classifier (:mod:`engine.models.stance`) on prepared shards.

Every frame of a training take where the head travels (faster than the gait planner's
``on_speed``) and one ankle is clearly slower than the other is a sample: the features of
the head's and hands' last half second, and whether the left foot is the slower one (the
stance foot). Mirrored shards give the left-right swapped samples.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from engine import skeleton as sk
from engine.constraints.gait import ANKLES
from engine.models.stance import N_FEATURES, StanceModel, stance_features, window_frames
from engine.solver.gait import GaitParams, arm_swing
from engine.training.data import shard_motions
from engine.training.perceptron import fit_perceptron

HEAD = sk.JOINT_INDEX["upperneck"]
HANDS = (sk.JOINT_INDEX["lwrist"], sk.JOINT_INDEX["rwrist"])
#: The gait planner's constants: its ``on_speed`` is a sample's least head speed, its arm
#: swing window and speed the arm rule's the samples are compared with.
GAIT = GaitParams()
#: Least difference of the two ankles' horizontal speeds (m/s) for a clear stance label.
MIN_GAP = 0.15


@dataclass(frozen=True)
class StanceSamples:
    """Features ``(N, N_FEATURES)``, labels ``(N,)`` (1: the left foot stands) and, per
    sample, the arm-swing rule's answer (1 left, 0 right, -1 no swing) for comparison."""

    x: np.ndarray
    y: np.ndarray
    arms: np.ndarray


def _speed(p: np.ndarray, fps: float) -> np.ndarray:
    """Horizontal speed ``(F, ...)`` of positions ``(F, ..., 3)``, central differences."""
    v = np.zeros(p.shape[:-1])
    if len(p) >= 3:
        v[1:-1] = np.linalg.norm(p[2:, ..., :2] - p[:-2, ..., :2], axis=-1) * fps / 2.0
        v[0], v[-1] = v[1], v[-2]
    return v


def clip_samples(pos: np.ndarray, fps: float) -> StanceSamples:
    """Samples of one clip's joint positions ``(F, 22, 3)`` (metres, z up)."""
    k = window_frames(fps)
    n = len(pos) - k + 1
    if n <= 0:
        return StanceSamples(np.zeros((0, N_FEATURES)), np.zeros(0), np.zeros(0))
    head = np.lib.stride_tricks.sliding_window_view(pos[:, HEAD], k, axis=0).transpose(0, 2, 1)
    hands = np.lib.stride_tricks.sliding_window_view(pos[:, list(HANDS)], k, axis=0).transpose(0, 3, 1, 2)
    ankles = _speed(pos[:, list(ANKLES)], fps)[k - 1 :]
    travel = np.linalg.norm(head[:, -1, :2] - head[:, 0, :2], axis=-1) * fps / (k - 1)
    keep = (travel > GAIT.on_speed) & (np.abs(ankles[:, 0] - ankles[:, 1]) > MIN_GAP)
    x = stance_features(head[keep], hands[keep], fps)
    assert x is not None
    y = (ankles[keep, 0] < ankles[keep, 1]).astype(np.float64)
    # the gait planner's arm-swing rule, over the same frames and the head's travel
    lag = max(1, round(GAIT.arm_lag_s * fps))
    diff = pos[:, HANDS[0], :2] - pos[:, HANDS[1], :2]
    t = np.arange(k - 1, len(pos))
    change = diff[t] - diff[np.maximum(t - lag, 0)]
    arms = arm_swing(change, head[:, -1, :2] - head[:, 0, :2], fps, lag, GAIT.arm_speed)[keep]
    return StanceSamples(x, y, arms.astype(np.float64))


def load_samples(data: Path, split: str, mirrored: bool = True) -> StanceSamples:
    """Samples of every shard of ``split`` in a prepared folder (its ``manifest.json``)."""
    parts = [clip_samples(m.positions, m.fps) for m in shard_motions(data, split, mirrored)]
    return StanceSamples(*(np.concatenate([getattr(p, f) for p in parts]) for f in ("x", "y", "arms")))


def train_stance(
    train: StanceSamples, hidden: int = 64, epochs: int = 30, lr: float = 2e-3, seed: int = 0
) -> StanceModel:
    """Fit the perceptron (two hidden layers of ``hidden``) with logistic loss, Adam."""
    import torch

    def loss(out, y):
        return torch.nn.functional.binary_cross_entropy_with_logits(out[:, 0], y)

    return StanceModel(*fit_perceptron(train.x, train.y, loss, hidden, epochs, lr, seed))


def accuracy(model: StanceModel, s: StanceSamples) -> dict[str, float]:
    """The classifier's and the arm rule's share of samples with the right stance foot
    (the arm rule's frames without a swing count as wrong; ``arms_coverage`` says how many
    it answers)."""
    p = model.left_stance(s.x)
    answered = s.arms >= 0
    return {
        "samples": float(len(s.y)),
        "model": float(((p > 0.5) == (s.y > 0.5)).mean()),
        "arms": float(((s.arms == s.y) & answered).mean()),
        "arms_coverage": float(answered.mean()),
        "arms_when_answering": float((s.arms[answered] == s.y[answered]).mean()) if answered.any() else float("nan"),
    }
