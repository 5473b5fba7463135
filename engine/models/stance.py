"""Which foot stands, from the head's and hands' last half second: a small learned classifier.

With head and hands only, the gait planner (:mod:`engine.solver.gait`) must know which foot
is in stance to plant it. The arms' swing says it on a steady walk, but not on a sneak, a
jog or a styled walk. The head also sways towards the stance foot and bobs once per step,
and the hands' swing has a shape as well as a sign; this classifier reads all of it. It is
a multilayer perceptron trained on the CMU training takes (``dragposer-studio train stance``,
:mod:`engine.training.stance`), evaluated in numpy here so that the solver needs no torch
for it.

The features (:func:`stance_features`) are written once and used by both training and the
solver: :data:`SAMPLES` samples over the last :data:`WINDOW_S` seconds of the head position
(relative to its current one) and of each hand relative to the head, in the frame of the
head's travel (x forward, y to the left, z up), and the travel speed.
"""

from __future__ import annotations

from pathlib import Path
from typing import ClassVar

import numpy as np

from engine.models.perceptron import Perceptron

#: Seconds of history the classifier reads.
WINDOW_S = 0.5
#: Samples over that window (evenly spaced, the last one the current frame).
SAMPLES = 11
#: Feature count: head (3) and two hands (6) per sample, and the speed.
N_FEATURES = SAMPLES * 9 + 1


def window_frames(fps: float) -> int:
    """Frames of history the features need at ``fps``."""
    return max(SAMPLES, round(WINDOW_S * fps) + 1)


def stance_features(head: np.ndarray, hands: np.ndarray, fps: float) -> np.ndarray | None:
    """Features ``(..., N_FEATURES)`` of windows of head ``(..., K, 3)`` and hands
    ``(..., K, 2, 3)`` positions (metres, z up, K = :func:`window_frames`, oldest first);
    None for a single window whose head did not travel (batched windows of a still head
    keep only their heights and the speed 0: there is no travel to turn into)."""
    head = np.asarray(head, dtype=np.float64)
    hands = np.asarray(hands, dtype=np.float64)
    idx = np.linspace(0, head.shape[-2] - 1, SAMPLES).round().astype(int)
    h = head[..., idx, :]
    w = hands[..., idx, :, :]
    d = h[..., -1, :2] - h[..., 0, :2]
    n = np.linalg.norm(d, axis=-1, keepdims=True)
    if head.ndim == 2 and float(n[0]) < 1e-6:
        return None
    f = d / np.maximum(n, 1e-9)
    rot = np.stack([f, np.stack([-f[..., 1], f[..., 0]], axis=-1)], axis=-2)  # (..., 2, 2)

    def local(v: np.ndarray) -> np.ndarray:
        """``v (..., SAMPLES, 3)`` turned into the travel's frame."""
        return np.concatenate([np.einsum("...ij,...sj->...si", rot, v[..., :2]), v[..., 2:]], axis=-1)

    head_rel = local(h - h[..., -1:, :])
    left = local(w[..., 0, :] - h)
    right = local(w[..., 1, :] - h)
    seconds = (head.shape[-2] - 1) / fps
    speed = n / seconds
    feats = np.concatenate([head_rel, left, right], axis=-1).reshape(*head.shape[:-2], SAMPLES * 9)
    return np.concatenate([feats, speed], axis=-1)


class StanceModel(Perceptron):
    """The trained classifier: feature normalisation and the perceptron's layers (one
    logistic output)."""

    KIND: ClassVar[str] = "stance"
    N_IN: ClassVar[int] = N_FEATURES
    N_OUT: ClassVar[int] = 1

    def left_stance(self, features: np.ndarray) -> np.ndarray:
        """Probability that the left foot stands, ``(...)``, from features ``(..., N_FEATURES)``."""
        return 1.0 / (1.0 + np.exp(-self.forward(features)[..., 0]))


#: The shipped classifier (``assets/models/stance.npz``, model card: "Stance classifier").
DEFAULT_STANCE = Path(__file__).resolve().parents[2] / "assets" / "models" / "stance.npz"
_DEFAULT: list[StanceModel | None] = []


def default_stance_model() -> StanceModel | None:
    """The shipped classifier, read once; None when the file is absent (the gait planner
    then goes by the arms' swing)."""
    if not _DEFAULT:
        _DEFAULT.append(StanceModel.load(DEFAULT_STANCE) if DEFAULT_STANCE.exists() else None)
    return _DEFAULT[0]
