"""Progress and cancelling of long work: bakes and range re-solves, the pose window's settle,
the studio's latent inspection.

A long solve takes two callables: ``progress(done, total)`` after every frame and
``cancelled() -> bool``, asked between frames. When ``cancelled()`` answers True the
solve raises :class:`Cancelled` before it touches anything it was given, so a
cancelled job leaves no trace. Both are plain callables, so the caller may run the work
on any thread (the studio runs it on a worker, see :mod:`engine.authoring.jobs`).
"""

from __future__ import annotations

from collections.abc import Callable

#: ``progress(done, total)``: frames done out of ``total``.
Progress = Callable[[int, int], None]
#: ``cancelled()``: True when the caller wants the work stopped.
CancelCheck = Callable[[], bool]


class Cancelled(Exception):
    """Raised by long work between two of its steps when its caller cancelled it."""


def check(cancelled: CancelCheck | None) -> None:
    """Raise :class:`Cancelled` when ``cancelled`` says so (None: never)."""
    if cancelled is not None and cancelled():
        raise Cancelled("cancelled")
