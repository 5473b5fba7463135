"""What a latent-space method keeps of its last frame's solve for latent debugging.

The method writes it, so it lives with the methods; :mod:`engine.latent` reads it and
runs methods, never the other way round.

:class:`SolveRecord` is valid until the method's next step: its constraints are the
method's own objects, whose targets the next frame's readings replace.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

from engine.solver.objective import active_weights

if TYPE_CHECKING:
    from engine.constraints.base import Constraint
    from engine.solver.frame import FrameContext, Solution

#: Where a frame's solve can start, as :attr:`SolveRecord.start` names it.
STARTS = ("predictor", "pose bank", "previous frame", "zero latent")


@dataclass(frozen=True)
class SolveRecord:
    """One frame's solve, as latent debugging replays it.

    Attributes
    ----------
    solution : Solution
        The solver's result (``solution.path``: the latents visited, ``(K, L)``).
    context : FrameContext
        The frame's context (decoding a latent needs it; ``context.prediction`` is the
        frame's prior latent).
    terms : tuple of (Constraint, float)
        The enabled terms of the solve with their weights for this frame (``weight``
        times ``activity``), zero-weight ones left out.
    start : str
        Where the solve started, one of :data:`STARTS`.
    """

    solution: "Solution"
    context: "FrameContext"
    terms: tuple[tuple["Constraint", float], ...]
    start: str


def record_of(
    solution: "Solution", context: "FrameContext", terms: "list[Constraint]", predicted: bool, bank: bool
) -> SolveRecord:
    """The :class:`SolveRecord` of a solve over ``terms`` (their weights taken now: the next
    frame changes them) that started from the frame's prior latent (``predicted``; from the
    pose bank when ``bank``) or else from the previous frame's latent (zero on frame 0)."""
    active, weights = active_weights(terms, context.frame)
    if predicted:
        start = "pose bank" if bank else "predictor"
    else:
        start = "previous frame" if context.frame else "zero latent"
    return SolveRecord(solution, context, tuple(zip(active, weights)), start)
