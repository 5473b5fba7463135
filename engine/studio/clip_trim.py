"""Trimming the studio's clip to a frame range, and what counts frames along with it.

Edit ▸ Trim clip to selection keeps frames ``first..last`` (inclusive) of the loaded
clip: :meth:`engine.motion.clip.Motion.trim` cuts the motion (the trackers are simulated
from it, so they follow). What else of the scene counts frames moves with them here, so
frame f of the trimmed clip shows the scene as frame ``f + first`` did:

* a constraint acting on ``frames = (start, end)`` only is shifted by ``-first``; a range
  cut partly is clamped into the kept frames (its blends are kept: the weights at the
  kept frames are those they had); one wholly outside the kept frames is **turned off**
  (``enabled = False``, its range clamped to the nearest kept frame), so it is still in
  the list to look at or re-enable, and :attr:`ClipTrim.turned_off` names it;
* a tracker's simulated failures (``failures``, half-open ``[a, b)`` windows) are shifted
  and clamped the same way; a failure wholly outside the kept frames is dropped.

Everything is pure: new objects, the inputs unchanged (the session replaces objects,
never edits them in place), so an undo puts the old ones back as they were.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence
from dataclasses import dataclass

from engine.constraints.base import Constraint
from engine.motion.clip import Motion
from engine.sensors import Sensor


@dataclass(frozen=True)
class ClipTrim:
    """The trimmed clip and its scene.

    Attributes
    ----------
    motion : Motion
        Frames ``first..last`` of the clip (``motion.start`` counts from the clip as loaded).
    constraints : tuple of Constraint
        In the same order, frame ranges shifted (see the module docs).
    sensors : tuple of Sensor
        In the same order, failures shifted.
    turned_off : tuple of str
        Names of the constraints turned off: they acted only outside the kept frames.
    """

    motion: Motion
    constraints: tuple[Constraint, ...]
    sensors: tuple[Sensor, ...]
    turned_off: tuple[str, ...]


def trim_constraint(c: Constraint, first: int, last: int) -> tuple[Constraint, bool]:
    """``c`` on the frames of a clip trimmed to ``first..last``; and whether it was turned
    off (its range wholly outside them). A constraint on every frame is ``c`` itself."""
    if c.frames is None:
        return c, False
    start, end = c.frames
    last_kept = last - first
    outside = end < first or start > last
    new = (min(max(start - first, 0), last_kept), min(max(end - first, 0), last_kept))
    if outside:
        return dataclasses.replace(c, frames=new, enabled=False), c.enabled
    return (c if new == c.frames else dataclasses.replace(c, frames=new)), False


def trim_failures(failures: tuple[tuple[int, int], ...], first: int, last: int) -> tuple[tuple[int, int], ...]:
    """Failure windows ``[a, b)`` on the frames of a clip trimmed to ``first..last``:
    shifted, clamped, the empty ones dropped."""
    kept = last - first + 1
    out = ((min(max(a - first, 0), kept), min(max(b - first, 0), kept)) for a, b in failures)
    return tuple((a, b) for a, b in out if a < b)


def trim_clip(
    motion: Motion, constraints: Sequence[Constraint], sensors: Sequence[Sensor], first: int, last: int
) -> ClipTrim:
    """Frames ``first..last`` (inclusive) of ``motion`` with ``constraints`` and ``sensors``
    moved with them (module docs).

    Raises
    ------
    UserError
        A range that is empty or outside the clip.
    """
    cut = motion.trim(first, last)
    moved = [trim_constraint(c, first, last) for c in constraints]
    out_sensors = tuple(
        s if not s.failures else dataclasses.replace(s, failures=trim_failures(s.failures, first, last))
        for s in sensors
    )
    return ClipTrim(cut, tuple(c for c, _ in moved), out_sensors, tuple(c.name for c, off in moved if off))
