"""Which way the pelvis faces, from six position-only trackers' last half second: a small
learned regressor.

With 3-DoF trackers on the hips, head, hands and feet (preset ``6x3dof``) nothing measures
the pelvis heading. The facing read off the feet's and hands' left-right lines
(:func:`engine.solver.pose.body_facing`) swings with every stride and every reach: 18
degrees from the truth's pelvis heading on average on the validation files. This network
reads the six trackers over the last :data:`WINDOW_S` seconds in the frame of that rough
facing and gives the correction to it, as a unit vector (cos, sin). It is a multilayer
perceptron trained on the CMU training takes (``dragposer-studio train heading``,
:mod:`engine.training.heading`), evaluated in numpy, and it reads only this frame's and
earlier readings, so it works live. DragPoser's reference heading follows what it says
when the hip tracker gives no rotation (:func:`engine.methods.dragposer_root.reference_root`).

The features (:func:`heading_features`) are written once and used by both training and the
solver.
"""

from __future__ import annotations

from pathlib import Path
from typing import ClassVar

import numpy as np

from engine.models.perceptron import Perceptron

#: The tracked joints the network reads, in this order (the trackers of preset ``6x3dof``).
JOINTS: tuple[str, ...] = ("root", "upperneck", "lwrist", "rwrist", "lankle", "rankle")
#: Seconds of history the network reads.
WINDOW_S = 0.5
#: Samples over that window (evenly spaced, the last one the current frame).
SAMPLES = 11
#: Feature count: every joint's position (3) per sample.
N_FEATURES = SAMPLES * len(JOINTS) * 3
#: Left/right pairs (indices into :data:`JOINTS`) whose horizontal lines give the rough
#: facing the features are turned into: the feet and the hands alike, as
#: :data:`engine.solver.pose.LATERAL_PAIRS` weighs them.
_PAIRS = ((4, 5), (2, 3))


def window_frames(fps: float) -> int:
    """Frames of history the features need at ``fps``."""
    return max(SAMPLES, round(WINDOW_S * fps) + 1)


def rough_yaw(pos: np.ndarray) -> np.ndarray:
    """Angle (radians, about +Z) of the rough facing of positions ``(..., 6, 3)`` of
    :data:`JOINTS`: the rotation that turns the canonical left (+X) onto the sum of the
    feet's and the hands' horizontal left-minus-right vectors ``(...)``."""
    lateral = sum(pos[..., a, :2] - pos[..., b, :2] for a, b in _PAIRS)
    return np.arctan2(lateral[..., 1], lateral[..., 0])


def heading_features(window: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Features ``(..., N_FEATURES)`` and the rough facing's angle ``(...)`` (radians) of
    windows ``(..., K, 6, 3)`` of :data:`JOINTS`' world positions (metres, z up, K =
    :func:`window_frames`, oldest first): :data:`SAMPLES` instants of every joint relative
    to the hips' current position, turned about the vertical so the rough facing of the
    current frame faces -Y. The network's answer is relative to that facing."""
    window = np.asarray(window, dtype=np.float64)
    idx = np.linspace(0, window.shape[-3] - 1, SAMPLES).round().astype(int)
    w = window[..., idx, :, :] - window[..., -1:, :1, :]  # relative to the hips now
    yaw = rough_yaw(window[..., -1, :, :])
    c, s = np.cos(yaw)[..., None, None], np.sin(yaw)[..., None, None]
    x, y = w[..., 0], w[..., 1]
    turned = np.stack([c * x + s * y, -s * x + c * y, w[..., 2]], axis=-1)  # rotated by -yaw
    return turned.reshape(*window.shape[:-3], N_FEATURES), yaw


class HeadingModel(Perceptron):
    """The trained regressor: feature normalisation and the perceptron's layers (two
    outputs, the correction's cosine and sine)."""

    KIND: ClassVar[str] = "heading"
    N_IN: ClassVar[int] = N_FEATURES
    N_OUT: ClassVar[int] = 2

    def correction(self, features: np.ndarray) -> np.ndarray:
        """Angle (radians) from the rough facing to the pelvis heading, ``(...)``, of
        features ``(..., N_FEATURES)``."""
        x = self.forward(features)
        return np.arctan2(x[..., 1], x[..., 0])

    def yaw(self, window: np.ndarray) -> np.ndarray:
        """Pelvis heading angle (radians about +Z, 0 facing -Y) of windows ``(..., K, 6, 3)``
        (:func:`heading_features`)."""
        x, rough = heading_features(window)
        return rough + self.correction(x)


#: The shipped model (``assets/models/heading.npz``, model card: "Heading network").
DEFAULT_HEADING = Path(__file__).resolve().parents[2] / "assets" / "models" / "heading.npz"
_DEFAULT: list[HeadingModel | None] = []


def default_heading_model() -> HeadingModel | None:
    """The shipped model, read once; None when the file is absent (the rough facing of the
    feet and hands is used as it is)."""
    if not _DEFAULT:
        _DEFAULT.append(HeadingModel.load(DEFAULT_HEADING) if DEFAULT_HEADING.exists() else None)
    return _DEFAULT[0]
