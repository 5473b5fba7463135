"""The latent-space pose solver (DragPoser's per-frame optimisation).

Public surface:

* :class:`PoseOptimizer` — ``solve(start, constraints, ctx) -> Solution`` per frame;
  ``decode(z, ctx) -> PoseState``; fast and reference paths (see :mod:`.optimizer`).
* :class:`OptimizerSettings` (validated), :data:`MODES`, :data:`OPTIMIZERS`, :data:`PRIORS`, :data:`FULL_SET`.
* :class:`FrameContext`, :class:`RootFrame`, :class:`RootOverride`, :class:`RootAnchor`
  (protocols :class:`BodyAnchor`, :class:`JointAnchor`) — what a frame's pose depends on besides the latent.
* :class:`Solution`, :class:`SolveTimings` — the result and where its time went
  (these and :class:`FrameContext`, :class:`LatentDecoder`: :mod:`.frame`).
* :class:`PoseState` — the pose constraints judge.
* :class:`TemporalSchedule` — when the temporal predictor runs (DragPoser sec. 4.3).
* :class:`LatentUpdate` — the Adam / gradient-step rules on a latent.
* Protocols :class:`LatentDecoder`, :class:`LatentPredictor`.
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:  # the real types for the checker; at run time each is imported on first use
    from engine.kinematics.pose_state import PoseState
    from engine.solver.frame import FrameContext, LatentDecoder, Solution, SolveTimings
    from engine.solver.optimizer import PoseOptimizer
    from engine.solver.pose import BodyAnchor, JointAnchor, RootAnchor, RootFrame, RootOverride
    from engine.solver.settings import FULL_SET, MODES, OPTIMIZERS, PRIORS, OptimizerSettings
    from engine.solver.temporal import LatentPredictor, TemporalSchedule
    from engine.solver.update import LatentUpdate

#: The module defining each public name. Imported on first use (PEP 562), so that
#: reading the settings (``engine.solver.settings``, e.g. to build the command line)
#: does not import torch.
_MODULES = {
    "frame": ("FrameContext", "LatentDecoder", "Solution", "SolveTimings"),
    "optimizer": ("PoseOptimizer",),
    "pose": ("BodyAnchor", "JointAnchor", "RootAnchor", "RootFrame", "RootOverride"),
    "settings": ("FULL_SET", "MODES", "OPTIMIZERS", "PRIORS", "OptimizerSettings"),
    "engine.kinematics.pose_state": ("PoseState",),
    "temporal": ("LatentPredictor", "TemporalSchedule"),
    "update": ("LatentUpdate",),
}
_WHERE = {name: module for module, names in _MODULES.items() for name in names}


def __getattr__(name: str) -> Any:
    where = _WHERE.get(name)
    if where is None:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    module = importlib.import_module(where if "." in where else f"{__name__}.{where}")
    value = getattr(module, name)
    globals()[name] = value
    return value


__all__ = [
    "FULL_SET",
    "MODES",
    "OPTIMIZERS",
    "PRIORS",
    "BodyAnchor",
    "FrameContext",
    "JointAnchor",
    "LatentDecoder",
    "LatentPredictor",
    "LatentUpdate",
    "OptimizerSettings",
    "PoseOptimizer",
    "PoseState",
    "RootAnchor",
    "RootFrame",
    "RootOverride",
    "Solution",
    "SolveTimings",
    "TemporalSchedule",
]
