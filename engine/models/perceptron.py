"""The forward pass of the project's small numpy perceptrons (the stance classifier, the
tracker networks): affine layers with a ReLU between them, evaluated without torch."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np


def relu_layers(x: np.ndarray, weights: Sequence[np.ndarray], biases: Sequence[np.ndarray]) -> np.ndarray:
    """``x (..., D_in)`` through layers ``x @ w + b``, ReLU after every layer but the last;
    ``(..., D_out)`` in ``x``'s and the layers' dtype."""
    for i, (w, b) in enumerate(zip(weights, biases, strict=True)):
        x = x @ w + b
        if i < len(weights) - 1:
            x = np.maximum(x, 0.0)
    return x
