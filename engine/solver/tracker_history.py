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
        # per frame: positions (6, 3), rotations (6, 4) and which joints were read (6,), in
        # BANK_JOINTS order, so a window is a few array operations, not a loop per value
        self.frames: list[tuple[np.ndarray, np.ndarray, np.ndarray]] = []

    def reset(self) -> None:
        self.frames.clear()

    def push(self, readings: dict[str, tuple[np.ndarray, np.ndarray]]) -> None:
        """Add one frame: connected bank joints -> (position (3,), rotation (4,))."""
        pos, rot = np.zeros((len(BANK_JOINTS), 3)), np.zeros((len(BANK_JOINTS), 4))
        read = np.zeros(len(BANK_JOINTS), dtype=bool)
        for j, (p, r) in readings.items():
            i = _COLUMN.get(j)
            if i is not None:
                pos[i], rot[i], read[i] = p, r, True
        self.frames.append((pos, rot, read))
        del self.frames[: -self.size]

    def arrays(self) -> tuple[tuple[str, ...], np.ndarray, np.ndarray] | None:
        """``(joints, pos (size, S, 3), rot (size, S, 4))`` of the joints connected in each
        of the last ``LAG + 1`` frames, oldest first, or None without an anchor among them
        or with fewer than two joints. Before a joint's first reading in the window (the
        clip's start, a tracker connected since) its earliest kept reading stands in, as
        the first frame does before a clip's start."""
        if not self.frames:
            return None
        read = np.array([f[2] for f in self.frames])  # (n, 6)
        kept = np.asarray(read[-(LAG + 1) :].all(axis=0))  # read in each of the last LAG + 1 frames
        joints = combination(j for j, ok in zip(BANK_JOINTS, kept, strict=True) if ok)
        if joints is None:
            return None
        cols = np.array([_COLUMN[j] for j in joints])
        n = len(self.frames)
        # each frame's own reading of a joint, else the next later one (the last frames have it)
        later = np.where(read[:, cols], np.arange(n)[:, None], n)
        rows = np.minimum.accumulate(later[::-1], axis=0)[::-1]
        rows = np.concatenate([np.repeat(rows[:1], self.size - n, axis=0), rows])  # the start repeated
        pos = np.array([f[0] for f in self.frames])[rows, cols]
        rot = np.array([f[1] for f in self.frames])[rows, cols]
        return joints, pos, rot


#: Column of each bank joint in a frame's arrays.
_COLUMN = {j: i for i, j in enumerate(BANK_JOINTS)}
