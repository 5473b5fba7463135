"""The trackers' recent readings that the tracker prior reads (:mod:`engine.solver.tracker_prior`'s
pose bank the last ``LAG + 1`` frames, :mod:`engine.solver.tracker_net`'s networks a longer
window), kept frame by frame as they arrive, live or from a clip.
"""

from __future__ import annotations

import numpy as np

from engine.solver.tracker_prior import BANK_JOINTS, LAG, combination


class TrackerHistory:
    """The last frames of readings of the bank joints: :meth:`PoseBank.latent` reads the
    last ``LAG + 1``, the tracker network (:mod:`engine.solver.tracker_net`) ``size``.

    Parameters
    ----------
    size : int
        Frames kept (at least ``LAG + 1``).
    """

    def __init__(self, size: int = LAG + 1) -> None:
        self.size = max(size, LAG + 1)
        self.frames: list[dict[str, tuple[np.ndarray, np.ndarray]]] = []

    def reset(self) -> None:
        self.frames.clear()

    def push(self, readings: dict[str, tuple[np.ndarray, np.ndarray]]) -> None:
        """Add one frame: connected bank joints -> (position (3,), rotation (4,))."""
        self.frames.append({j: r for j, r in readings.items() if j in BANK_JOINTS})
        del self.frames[: -self.size]

    def arrays(self) -> tuple[tuple[str, ...], np.ndarray, np.ndarray] | None:
        """``(joints, pos (size, S, 3), rot (size, S, 4))`` of the joints connected in each
        of the last ``LAG + 1`` frames, oldest first, or None without an anchor among them
        or with fewer than two joints. Before a joint's first reading in the window (the
        clip's start, a tracker connected since) its earliest kept reading stands in, as
        the first frame does before a clip's start."""
        if not self.frames:
            return None
        recent = self.frames[-(LAG + 1) :]
        joints = combination(j for j in BANK_JOINTS if all(j in f for f in recent))
        if joints is None:
            return None
        pos = np.empty((self.size, len(joints), 3))
        rot = np.empty((self.size, len(joints), 4))
        pad = self.size - len(self.frames)
        for s, j in enumerate(joints):
            held = self.frames[-1][j]
            for t in range(len(self.frames) - 1, -1, -1):  # newest first, gaps take the later reading
                held = self.frames[t].get(j, held)
                pos[pad + t, s], rot[pad + t, s] = held
            pos[:pad, s], rot[:pad, s] = held
        return joints, pos, rot
