"""The latent-space pose solver (DragPoser's per-frame optimisation).

Public surface:

* :class:`PoseOptimizer` — ``solve(start, constraints, ctx) -> Solution`` per frame;
  ``decode(z, ctx) -> PoseState``; fast and reference paths (see :mod:`.optimizer`).
* :class:`OptimizerSettings` (validated), :data:`MODES`, :data:`OPTIMIZERS`, :data:`PRIORS`, :data:`FULL_SET`.
* :class:`FrameContext`, :class:`RootFrame`, :class:`RootOverride`, :class:`RootAnchor`
  — what a frame's pose depends on besides the latent.
* :class:`Solution`, :class:`SolveTimings` — the result and where its time went
  (these and :class:`FrameContext`, :class:`LatentDecoder`: :mod:`.frame`).
* :class:`PoseState` — the pose constraints judge.
* :class:`TemporalSchedule` — when the temporal predictor runs (DragPoser sec. 4.3).
* :class:`LatentUpdate` — the Adam / gradient-step rules on a latent.
* Protocols :class:`LatentDecoder`, :class:`LatentPredictor`.
"""

from engine.solver.frame import FrameContext, LatentDecoder, Solution, SolveTimings
from engine.solver.optimizer import PoseOptimizer
from engine.solver.pose import RootAnchor, RootFrame, RootOverride, world_root
from engine.solver.settings import FULL_SET, MODES, OPTIMIZERS, PRIORS, OptimizerSettings
from engine.kinematics.pose_state import PoseState
from engine.solver.temporal import LatentPredictor, TemporalSchedule
from engine.solver.update import LatentUpdate

__all__ = [
    "FULL_SET", "MODES", "OPTIMIZERS", "PRIORS", "FrameContext", "LatentDecoder", "LatentPredictor", "LatentUpdate",
    "OptimizerSettings", "PoseOptimizer", "PoseState", "RootAnchor", "RootFrame", "RootOverride", "Solution",
    "SolveTimings", "TemporalSchedule", "world_root",
]  # fmt: skip
