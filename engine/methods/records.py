"""Per-frame results of a long run kept in preallocated arrays (``run_method(light=True)``).

A :class:`FrameResult` per frame costs about 1.7 kB of Python objects (the result, its
array views, a losses dict, a timings dict, a latent array), so a 10,000-frame
reconstruction grew by ~17 MB while it ran. :class:`ResultArrays` stores the same
figures in arrays allocated (and written) when the run starts, and builds a
``FrameResult`` only when one is asked for, so memory stays flat over the clip.
"""

from __future__ import annotations

from collections.abc import Iterator, Sequence

import numpy as np

from engine import skeleton as sk
from engine.methods.base import FrameResult

#: The per-iteration timing parts of :attr:`FrameResult.timings`, in array column order.
TIMING_KEYS = ("ms_per_iteration", "decoder", "fk_losses", "backward", "step")


class ResultArrays(Sequence[FrameResult]):
    """``n`` frames' results; frame ``i`` is written by :meth:`store` and read back as a
    :class:`FrameResult` whose pose fields are views into the arrays and whose ``losses``
    keep only the final ``total``.

    Attributes
    ----------
    local_rot : ndarray (n, 22, 4)
    root_pos : ndarray (n, 3)
    positions : ndarray (n, 22, 3)
    """

    def __init__(self, n: int) -> None:
        # np.full writes every page now: the memory is taken at the start, not as frames arrive
        self.local_rot = np.full((n, sk.NUM_JOINTS, 4), np.nan)
        self.root_pos = np.full((n, 3), np.nan)
        self.positions = np.full((n, sk.NUM_JOINTS, 3), np.nan)
        self.iterations = np.zeros(n, dtype=np.int64)
        self.ms = np.zeros(n)
        self.total = np.full(n, np.nan)  # final total loss; NaN: the method reported none
        self.timings = np.full((n, len(TIMING_KEYS)), np.nan)
        self.latent: np.ndarray | None = None  # (n, L), allocated at the first latent
        self.warnings: dict[int, list[str]] = {}  # only frames that have some
        self._n = 0

    def store(self, i: int, res: FrameResult) -> None:
        """Copy frame ``i``'s result into the arrays (frames arrive in order)."""
        self.local_rot[i], self.root_pos[i], self.positions[i] = res.local_rot, res.root_pos, res.positions
        self.iterations[i], self.ms[i] = res.iterations, res.ms
        if res.losses:
            self.total[i] = res.losses[-1].get("total", np.nan)
        if res.timings:
            self.timings[i] = [res.timings.get(k, np.nan) for k in TIMING_KEYS]
        if res.latent is not None:
            z = np.asarray(res.latent).reshape(-1)
            if self.latent is None:
                self.latent = np.full((len(self.ms), z.size), np.nan, dtype=np.float32)
            self.latent[i] = z
        if res.warnings:
            self.warnings[i] = list(res.warnings)
        self._n = max(self._n, i + 1)

    def __len__(self) -> int:
        return self._n

    def __getitem__(self, i):
        if isinstance(i, slice):
            return [self[k] for k in range(*i.indices(self._n))]
        if i < 0:
            i += self._n
        if not 0 <= i < self._n:
            raise IndexError(f"frame {i} of {self._n}")
        total = self.total[i]
        t = self.timings[i]
        return FrameResult(
            local_rot=self.local_rot[i],
            root_pos=self.root_pos[i],
            positions=self.positions[i],
            iterations=int(self.iterations[i]),
            losses=[] if np.isnan(total) else [{"total": float(total)}],
            latent=None if self.latent is None else self.latent[i],
            ms=float(self.ms[i]),
            warnings=list(self.warnings.get(i, ())),
            timings={} if np.isnan(t[0]) else dict(zip(TIMING_KEYS, t.tolist())),
        )

    def __iter__(self) -> Iterator[FrameResult]:
        return (self[i] for i in range(self._n))
