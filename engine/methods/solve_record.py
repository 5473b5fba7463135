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

#: Where a frame's solve can start, as :attr:`SolveRecord.start` names it (or "solved
#: frame N": the latent of clip frame N, solved last, e.g. before a seek).
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
    solution: "Solution",
    context: "FrameContext",
    terms: "list[Constraint]",
    predicted: bool,
    bank: bool,
    previous: int | None = -1,
) -> SolveRecord:
    """The :class:`SolveRecord` of a solve over ``terms`` (their weights taken now: the next
    frame changes them) that started from the frame's prior latent (``predicted``; from the
    pose bank when ``bank``) or else from the latent of the clip frame the method solved
    before, ``previous``: None when it solved none since its reset (the zero latent); -1
    (the default) for the frame before this one, or none on frame 0.

    A seek within two seconds ahead keeps the method's state, so its first solve starts
    from the frame solved before the seek, not the one before it: said as "solved frame N".
    """
    active, weights = active_weights(terms, context.frame)
    if previous == -1:
        previous = context.frame - 1 if context.frame else None
    if predicted:
        start = "pose bank" if bank else "predictor"
    elif previous is None:
        start = "zero latent"
    elif previous == context.frame - 1:
        start = "previous frame"
    else:
        start = f"solved frame {previous}"
    return SolveRecord(solution, context, tuple(zip(active, weights)), start)
