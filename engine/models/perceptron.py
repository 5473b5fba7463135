"""The project's small numpy perceptrons (the stance classifier, the heading network, the
tracker networks): affine layers with a ReLU between them, evaluated without torch, and
(:class:`Perceptron`) the standardised-input model with one file format that the stance
classifier and the heading network share."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import ClassVar, TypeVar

import numpy as np

P = TypeVar("P", bound="Perceptron")


def relu_layers(x: np.ndarray, weights: Sequence[np.ndarray], biases: Sequence[np.ndarray]) -> np.ndarray:
    """``x (..., D_in)`` through layers ``x @ w + b``, ReLU after every layer but the last;
    ``(..., D_out)`` in ``x``'s and the layers' dtype."""
    for i, (w, b) in enumerate(zip(weights, biases, strict=True)):
        x = x @ w + b
        if i < len(weights) - 1:
            x = np.maximum(x, 0.0)
    return x


@dataclass(frozen=True)
class Perceptron:
    """Input standardisation and a perceptron's layers (ReLU between them), float64 in memory,
    float32 on disk. A subclass names what it is (:attr:`KIND`, for messages) and its input and
    output sizes (:attr:`N_IN`, :attr:`N_OUT`), which :meth:`load` checks."""

    mean: np.ndarray
    std: np.ndarray
    weights: tuple[np.ndarray, ...]
    biases: tuple[np.ndarray, ...]

    KIND: ClassVar[str] = "perceptron"
    N_IN: ClassVar[int] = 0
    N_OUT: ClassVar[int] = 0

    def forward(self, features: np.ndarray) -> np.ndarray:
        """Outputs ``(..., N_OUT)`` of inputs ``(..., N_IN)``."""
        return relu_layers((np.asarray(features, dtype=np.float64) - self.mean) / self.std, self.weights, self.biases)

    def save(self, path: Path) -> None:
        """Write the model as an ``.npz`` (``mean``, ``std``, ``w0``, ``b0``, ...), atomically."""
        from engine.atomic import atomic_path

        arrays = {"mean": self.mean, "std": self.std}
        for i, (w, b) in enumerate(zip(self.weights, self.biases, strict=True)):
            arrays[f"w{i}"] = w.astype(np.float32)
            arrays[f"b{i}"] = b.astype(np.float32)
        with atomic_path(path, suffix=".npz") as tmp:
            np.savez(tmp, **arrays)  # type: ignore[arg-type]  # numpy's stubs: **arrays could name allow_pickle

    @classmethod
    def load(cls: type[P], path: Path) -> P:
        """Read a model written by :meth:`save`; a file that is not one, or one of other sizes,
        is named with what is wrong (:class:`engine.errors.UserError`)."""
        from engine.errors import UserError

        try:
            with np.load(path, allow_pickle=False) as z:
                missing = [k for k in ("mean", "std", "w0", "b0") if k not in z.files]
                if missing:
                    raise UserError(f"{path}: not a {cls.KIND} model (no {', '.join(missing)})")
                n = sum(1 for k in z.files if k.startswith("w"))
                sizes = (z["mean"].shape[0], z[f"w{n - 1}"].shape[1])
                if z["mean"].shape != (cls.N_IN,) or z["w0"].shape[0] != cls.N_IN or sizes[1] != cls.N_OUT:
                    raise UserError(
                        f"{path}: a {cls.KIND} model for {sizes[0]} inputs and {sizes[1]} outputs, "
                        f"not {cls.N_IN} and {cls.N_OUT}"
                    )
                return cls(
                    z["mean"].astype(np.float64),
                    z["std"].astype(np.float64),
                    tuple(z[f"w{i}"].astype(np.float64) for i in range(n)),
                    tuple(z[f"b{i}"].astype(np.float64) for i in range(n)),
                )
        except (OSError, ValueError, KeyError) as exc:
            raise UserError(f"{path}: not a {cls.KIND} model ({exc})") from exc
