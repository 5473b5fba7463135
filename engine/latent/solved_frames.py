"""Every frame solved since a clip (or method) was opened, with its newest readouts.

The engine publishes the readouts of its recent solves (``snap.history``, restarted at
each jump: a seek backwards, a loop, a load). The studio's latent map, readouts chart,
flag marks on the timeline and *Next flagged frame* all read one :class:`SolvedFrames`
fed from those histories, so a seek that restarts the engine's history erases nothing,
and a frame's place on the map, its readouts and its flag always come from the same
solve (the flag is the verdict :func:`engine.latent.readouts.flag` gave that solve).

A frame solved again (a seek lands on it, an edit re-solves it) takes its new solve's
readouts. A seek solves from other temporal state than playback did, so a frame flagged
in playback may come out unflagged after *Next flagged frame* lands on it:
:meth:`SolvedFrames.earlier_flag` keeps the flagged solve's readouts so the studio can
say so instead of showing readouts that contradict the jump.

Numpy only.
"""

from __future__ import annotations

from collections.abc import Iterable
from typing import Any

import numpy as np

from engine.latent.readouts import next_flagged

#: The readouts a history entry carries (:meth:`engine.studio.latent_views.LatentView.readouts`).
FIELDS = ("x", "y", "nearest", "norm", "predictor", "flagged")


def entry_key(entry: Any) -> tuple:
    """What tells one solve's history entry from another's: the snapshots of an engine in
    its own process arrive unpickled, so the same entry is a new object every time."""
    return entry.frame, entry.ms, entry.iterations


class SolvedFrames:
    """Frame -> the newest readouts of its solve (see the module doc).

    ``version`` counts the changes, so views redraw only when it moves.
    """

    def __init__(self) -> None:
        self._rows: dict[int, dict[str, float]] = {}
        self._earlier: dict[int, dict[str, float]] = {}
        self._last: tuple | None = None  # the key of the newest history entry read
        self.version = 0
        self._cache: tuple[int, np.ndarray, np.ndarray] | None = None

    def clear(self) -> None:
        """Forget every frame (another clip or method)."""
        self._rows.clear()
        self._earlier.clear()
        self._last = None
        self.version += 1

    def note(self, history: Iterable[Any]) -> bool:
        """Read the entries of ``history`` (oldest first) newer than the last one read;
        True when a frame was added or changed."""
        entries = list(history)
        new = []
        for r in reversed(entries):
            if entry_key(r) == self._last:
                break
            if r.readouts:
                new.append(r)
        if entries:
            self._last = entry_key(entries[-1])
        for r in reversed(new):  # oldest first: the newest solve of a frame wins
            row = {k: float(r.readouts.get(k, np.nan)) for k in FIELDS}
            old = self._rows.get(r.frame)
            if old is not None and old["flagged"] > 0 and row["flagged"] <= 0:
                self._earlier[r.frame] = old
            elif row["flagged"] > 0:
                self._earlier.pop(r.frame, None)
            self._rows[r.frame] = row
        if new:
            self.version += 1
        return bool(new)

    def __len__(self) -> int:
        return len(self._rows)

    def _table(self) -> tuple[np.ndarray, np.ndarray]:
        if self._cache is None or self._cache[0] != self.version:
            frames = np.array(sorted(self._rows), int)
            table = np.array([[self._rows[f][k] for k in FIELDS] for f in frames], float).reshape(-1, len(FIELDS))
            self._cache = (self.version, frames, table)
        return self._cache[1], self._cache[2]

    @property
    def frames(self) -> np.ndarray:
        """The solved frames, ascending ``(F,)`` int."""
        return self._table()[0]

    def column(self, name: str) -> np.ndarray:
        """Readout ``name`` (one of :data:`FIELDS`) of every frame of :attr:`frames`, ``(F,)``."""
        return self._table()[1][:, FIELDS.index(name)]

    @property
    def xy(self) -> np.ndarray:
        """Map coordinates of every frame of :attr:`frames`, ``(F, 2)``."""
        return self._table()[1][:, :2]

    @property
    def flagged(self) -> np.ndarray:
        """The flag verdict of every frame of :attr:`frames`, ``(F,)`` bool."""
        return self.column("flagged") > 0

    @property
    def flagged_frames(self) -> list[int]:
        return [int(f) for f in self.frames[self.flagged]]

    def row(self, frame: int) -> dict[str, float] | None:
        """Frame ``frame``'s newest readouts by name (``flagged`` 0.0 / 1.0), None if unsolved."""
        return self._rows.get(int(frame))

    def earlier_flag(self, frame: int) -> dict[str, float] | None:
        """The readouts of an earlier solve of ``frame`` that was flagged, when its newest
        solve is not (see the module doc); None otherwise."""
        return self._earlier.get(int(frame))

    def next_flagged(self, after: int) -> int | None:
        """The first flagged frame after ``after``, wrapping to the first; None if none."""
        return next_flagged(self.flagged, self.frames, after)
