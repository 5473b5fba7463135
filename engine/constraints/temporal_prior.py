"""``temporal_prior``: stay near the temporal predictor's latent (DragPoser Algorithm 1).

Loss: mean squared difference between the latent being optimised and the predictor's
latent for the frame (:attr:`FrameInputs.prediction`); zero when there is no prediction
yet. The residual is ``(z - z_pred) / sqrt(L)``, a term on the latent itself: its
gradient ``2 (z - z_pred) / L`` skips the decoder.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, ClassVar

import numpy as np

from engine.constraints.base import Constraint
from engine.constraints.residual import FrameInputs, FrameRows, Kit, Residuals, Term


@dataclass
class TemporalPriorConstraint(Constraint):
    """MSE between the latent and the temporal predictor's latent (no parameters)."""

    kind: ClassVar[str] = "temporal_prior"
    user_facing: ClassVar[bool] = False  # built by DragPoser from its predictor

    def acts_on(self) -> tuple[str, ...]:
        return ()

    def term(self, frame: FrameInputs) -> "PriorTerm":
        return PriorTerm(self.name, frame.prediction)

    @classmethod
    def examples(cls, positions: np.ndarray) -> list[Constraint]:
        return [cls(weight=0.5)]


class PriorTerm(FrameRows, Term):
    """``(z - prediction) / sqrt(L)`` per frame; ``prediction (A, L)``, or None (no
    prediction: the residual is zero)."""

    PER_FRAME: tuple[str, ...] = ("prediction",)

    def __init__(self, name: str, prediction: np.ndarray | None) -> None:
        self.names = (name,)
        pred = None if prediction is None else np.asarray(prediction, dtype=np.float64).reshape(1, -1)
        self.prediction = pred
        self.owner = np.zeros(1 if pred is None else pred.shape[1], dtype=np.intp)
        if pred is None:
            self.PER_FRAME = ()

    def residual(self, kit: Kit, P: Any, W: Any, z: Any, jac: bool = False, rows: Any = None) -> Residuals:
        a, n = z.shape
        if self.prediction is None:
            return Residuals(kit.zeros((a, 1), z))
        s = 1.0 / math.sqrt(n)
        r = (z - kit.const(self.prediction[self.select(z, rows)], z)) * s
        if not jac:
            return Residuals(r)
        d = getattr(self, "_d_latent", None)
        if d is None or d.shape[:2] != (a, n):  # the same for every evaluation: made once
            d = self._d_latent = np.broadcast_to(np.eye(n) * s, (a, n, n))
        return Residuals(r, d_latent=d)
