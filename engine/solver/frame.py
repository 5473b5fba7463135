"""What one frame's solve takes and gives back (the types of
:meth:`engine.solver.PoseOptimizer.solve`; the solve itself is :mod:`engine.solver.optimizer`).

* :class:`LatentDecoder` — what the optimizer needs from the pose VAE: latent ``(B, L)``
  to local rotations ``(B, 22, 4)`` and root displacement ``(B, 3)`` metres.
* :class:`FrameContext` — everything the decoded pose depends on besides the latent
  (previous root, hip tracker or head anchor, previous positions, the temporal
  predictor's latent, frame index, deadline).
* :class:`Solution` — the detached result: latent ``(L,)``, its :class:`PoseState`, the
  losses per iteration, warnings, and :class:`SolveTimings` (milliseconds per part).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Protocol

import numpy as np
import torch

from engine.kinematics.pose_state import PoseState
from engine.solver.pose import BodyAnchor, RootFrame, RootOverride


class LatentDecoder(Protocol):
    """What the optimizer needs from the pose VAE (``engine.models.PoseVAE`` fits)."""

    def decode(self, z: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor]:
        """``z (B, L)`` -> unit quaternions ``rot (B, 22, 4)`` and ``disp (B, 3)`` metres."""
        ...


@dataclass
class FrameContext:
    """Everything about a frame the decoded pose depends on besides the latent.

    Attributes
    ----------
    previous_root : RootFrame
        The previous frame's solved root (heading and position reference).
    root_override : RootOverride or None
        Connected hip sensor, which dictates the root.
    root_anchor : BodyAnchor or None
        Without a hip sensor: what places the body (a :class:`~engine.solver.pose.RootAnchor`:
        the joint, the head, whose tracker does; the fast objective takes only a
        :class:`~engine.solver.pose.JointAnchor`).
    previous_positions : Tensor (22, 3) or None
        Previous frame's solved joint positions, metres.
    prediction : Tensor (L,) or None
        Temporal predictor's latent for this frame.
    frame : int
        Frame index.
    deadline : float or None
        ``time.perf_counter()`` time by which the solve should end
        (:mod:`engine.solver.optimizer` says how); None: no limit.
    """

    previous_root: RootFrame
    root_override: RootOverride | None = None
    root_anchor: BodyAnchor | None = None
    previous_positions: torch.Tensor | None = None
    prediction: torch.Tensor | None = None
    frame: int = 0
    deadline: float | None = None


@dataclass
class SolveTimings:
    """Where one frame's solve spent its time, milliseconds summed over its iterations.

    ``decoder`` is the decoder's forward pass, ``fk_losses`` the root, FK and loss terms,
    ``backward`` the gradient, ``step`` the latent update; ``fast`` tells which objective
    ran (numpy or the autograd reference).
    """

    iterations: int = 0
    decoder: float = 0.0
    fk_losses: float = 0.0
    backward: float = 0.0
    step: float = 0.0
    fast: bool = False

    def per_iteration(self) -> dict[str, float]:
        """Milliseconds per iteration: each part and their sum ``ms_per_iteration``."""
        n = max(self.iterations, 1)
        parts = {k: getattr(self, k) / n for k in ("decoder", "fk_losses", "backward", "step")}
        return {"ms_per_iteration": sum(parts.values()), **parts}


@dataclass
class Solution:
    """Result of one frame's optimisation (all detached).

    Attributes
    ----------
    latent : Tensor (L,)
    state : PoseState
        Decoded pose of ``latent``.
    losses : list of dict
        ``losses[k]`` = every term (by constraint name) and ``"total"`` at the latent
        after ``k`` steps; ``len(losses) == iterations + 1``.
    iterations : int
        Update steps taken.
    warnings : list of str
    fell_back : bool
        True when the solve was abandoned for the starting latent.
    timings : SolveTimings
    cut : bool
        True when the frame's deadline stopped the solve before ``iterations`` steps.
    path : ndarray (K, L) float32 or None
        The latents the solve visited, from the start (row 0) to the last one evaluated;
        ``K == len(losses)`` (latent-space debugging draws it).
    """

    latent: torch.Tensor
    state: PoseState
    losses: list[dict[str, float]] = field(default_factory=list)
    iterations: int = 0
    warnings: list[str] = field(default_factory=list)
    fell_back: bool = False
    timings: SolveTimings = field(default_factory=SolveTimings)
    cut: bool = False
    path: "np.ndarray | None" = None
