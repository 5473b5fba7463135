"""Saying so when a frame leaves the fast path because a constraint kind has no fast term.

A kind declares its fast-path term in its own module
(:meth:`engine.constraints.base.Constraint.fast_term`); one that does not is still solved,
by the slower autograd reference path, and this is never silent: every such frame is
flagged (:attr:`~engine.solver.frame.Solution.slow_kinds`, ``slow_path`` in its
per-iteration timings, which the studio shows), the first frame of each set of kinds
carries a warning line, and the process warns once (:class:`SlowPathWarning`, printed by
the command line).
"""

from __future__ import annotations

from warnings import warn

from engine.solver.frame import Solution

_WARNED: set[tuple[str, ...]] = set()  # sets of slow kinds warned about in this process


class SlowPathWarning(UserWarning):
    """Constraint kinds without a fast-path term made frames use the reference path."""


def report_slow(sol: Solution, slow: tuple[str, ...], reported: set[tuple[str, ...]]) -> None:
    """Flag ``sol`` as slowed by the kinds ``slow`` (sorted); ``reported`` holds the sets
    of kinds the calling solver has put in a frame's warnings already (updated)."""
    sol.slow_kinds = sol.timings.slow_kinds = slow
    if slow in reported:
        return
    reported.add(slow)
    msg = f"no fast-path term for constraint kind(s) {', '.join(slow)}: solved on the slower reference path"
    sol.warnings.append(msg)
    if slow not in _WARNED:
        _WARNED.add(slow)
        warn(msg, SlowPathWarning, stacklevel=4)
