"""``temporal_prior``: stay near the temporal predictor's latent (DragPoser Algorithm 1).

Loss: mean squared difference between the latent being optimised and the predictor's
latent for the frame (``PoseState.prediction``); zero when there is no prediction yet.
The solver's fast path evaluates it on the latent itself (a :class:`NativeTerm`: the
gradient ``2 (z - z_pred) / L`` skips the decoder).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar, TYPE_CHECKING


from engine.constraints.base import Constraint
from engine.constraints.terms import FrameInputs, NativeTerm

if TYPE_CHECKING:  # torch is imported by the code that runs a loss (the engine), not by editors
    import torch

    from engine.kinematics.pose_state import PoseState


@dataclass
class TemporalPriorConstraint(Constraint):
    """MSE between the latent and the temporal predictor's latent (no parameters)."""

    kind: ClassVar[str] = "temporal_prior"
    user_facing: ClassVar[bool] = False  # built by DragPoser from its predictor

    def acts_on(self) -> tuple[str, ...]:
        return ()

    def fast_term(self, frame: FrameInputs) -> NativeTerm:
        return NativeTerm(self, self.weight)

    def loss(self, state: PoseState) -> torch.Tensor:
        if state.prediction is None:
            return state.latent.new_zeros(())
        return ((state.latent - state.prediction.detach()) ** 2).mean()
