"""A live run's per-frame figures in bounded memory: the last minute of frames as they
came, and summaries of the whole run that do not grow with its length.

A stream of an hour at 60 Hz solves 216,000 frames; a list per figure (latency, solve
time, iterations, fresh devices) grew the ``live`` process by about 0.4 MiB a minute
(docs/reliability.md). :class:`FrameFigures` keeps the newest :data:`RECENT_FRAMES` of
each figure (the status line and the soak read those) and, for the whole run, exact
counts (iterations and fresh devices take few distinct values) and the latency and
solve-time percentiles from a fixed histogram (:class:`LogHistogram`), exact while
the run is shorter than the recent window.
"""

from __future__ import annotations

import math
from collections import Counter, deque

import numpy as np

#: Frames of each figure kept as they came: a minute at 60 Hz.
RECENT_FRAMES = 3600


def percentile_of_counts(counts: Counter[int], q: float) -> float:
    """The ``q``-th percentile (0-100) of the integers counted in ``counts``
    (value -> how often), as :func:`numpy.percentile` of the expanded values gives it
    (linear interpolation), without expanding them."""
    values = np.array(sorted(counts), float)
    cum = np.cumsum([counts[int(v)] for v in values])
    rank = q / 100.0 * (cum[-1] - 1)
    lo, hi = math.floor(rank), math.ceil(rank)
    a = values[np.searchsorted(cum, lo, side="right")]
    b = values[np.searchsorted(cum, hi, side="right")]
    return float(a + (b - a) * (rank - lo))


class LogHistogram:
    """Counts of non-negative values (milliseconds) in geometric bins :data:`RATIO` wide,
    from :data:`LOW` to :data:`HIGH` ms (smaller values count in the first bin, larger
    in the last), with the exact minimum and maximum: a fixed size whatever the count.

    A percentile is the geometric centre of the bin that holds it, clamped to the
    exact extremes: within half a bin (0.5 %) of the value
    :func:`numpy.percentile` gives where neighbouring values are dense, as a run's
    latencies are.
    """

    LOW, HIGH, RATIO = 1e-3, 1e6, 1.01

    def __init__(self) -> None:
        self._log_ratio = math.log(self.RATIO)
        n = math.ceil(math.log(self.HIGH / self.LOW) / self._log_ratio)
        self.counts = np.zeros(n, np.int64)
        self.count = 0
        self.min = math.inf
        self.max = -math.inf

    def add(self, value: float) -> None:
        """Count ``value`` (ms)."""
        k = 0 if value <= self.LOW else int(math.log(value / self.LOW) / self._log_ratio)
        self.counts[min(k, self.counts.size - 1)] += 1
        self.count += 1
        self.min = min(self.min, value)
        self.max = max(self.max, value)

    def percentile(self, q: float) -> float:
        """The ``q``-th percentile (0-100), ms (see the class doc); NaN when empty."""
        if not self.count:
            return math.nan
        if q <= 0 or q >= 100:
            return float(self.min if q <= 0 else self.max)
        rank = math.floor(q / 100.0 * (self.count - 1))
        k = int(np.searchsorted(np.cumsum(self.counts), rank, side="right"))
        centre = self.LOW * self.RATIO ** (k + 0.5)
        return float(min(max(centre, self.min), self.max))


class FrameFigures:
    """Figures of every solved frame of a live run (see the module doc).

    Attributes
    ----------
    frames : int
        Frames added.
    latency_ms, solve_ms : deque of float
        Packet arrival to solved pose, and the method's own time, of the newest
        :data:`RECENT_FRAMES` frames, milliseconds.
    iterations, fresh, devices : deque of int
        Optimizer iterations, and the mapped devices that sent a sample for the frame
        of those seen so far, of the newest frames.
    """

    def __init__(self, recent: int = RECENT_FRAMES) -> None:
        self.frames = 0
        self.latency_ms: deque[float] = deque(maxlen=recent)
        self.solve_ms: deque[float] = deque(maxlen=recent)
        self.iterations: deque[int] = deque(maxlen=recent)
        self.fresh: deque[int] = deque(maxlen=recent)
        self.devices: deque[int] = deque(maxlen=recent)
        self._latency = LogHistogram()
        self._solve = LogHistogram()
        self._iterations: Counter[int] = Counter()
        self._fresh: Counter[int] = Counter()
        self._complete = 0
        self._devices = 0

    def add(self, latency_ms: float, solve_ms: float, iterations: int, fresh: int, devices: int) -> None:
        """One solved frame's figures (ms, ms, count, devices, devices)."""
        self.frames += 1
        self.latency_ms.append(latency_ms)
        self.solve_ms.append(solve_ms)
        self.iterations.append(iterations)
        self.fresh.append(fresh)
        self.devices.append(devices)
        self._latency.add(latency_ms)
        self._solve.add(solve_ms)
        self._iterations[int(iterations)] += 1
        self._fresh[int(fresh)] += 1
        self._complete += fresh >= devices
        self._devices = max(self._devices, int(devices))

    def _all_recent(self) -> bool:
        return self.frames == len(self.latency_ms)

    def _percentile(self, recent: deque[float], histogram: LogHistogram, q: float) -> float:
        if self._all_recent():  # every value is still here: exact
            return float(np.percentile(np.asarray(recent, float), q))
        return histogram.percentile(q)

    def latency_summary(self) -> dict:
        """Median, 95th percentile and maximum latency of the run, ms (None before a frame)."""
        if not self.frames:
            return {"p50": None, "p95": None, "max": None}
        return {
            "p50": self._percentile(self.latency_ms, self._latency, 50),
            "p95": self._percentile(self.latency_ms, self._latency, 95),
            "max": float(self._latency.max),
        }

    def solve_median_ms(self) -> float | None:
        """The median of the method's time per frame over the run, ms."""
        return self._percentile(self.solve_ms, self._solve, 50) if self.frames else None

    def iteration_summary(self) -> dict:
        """Median, mean, 5th percentile and minimum of the iterations per solved frame."""
        if not self.frames:
            return {"median": None, "mean": None, "p5": None, "min": None}
        c = self._iterations
        return {
            "median": percentile_of_counts(c, 50),
            "mean": sum(v * n for v, n in c.items()) / self.frames,
            "p5": percentile_of_counts(c, 5),
            "min": min(c),
        }

    def completeness_summary(self) -> dict:
        """How complete the solved frames were: frames whose every mapped device seen so far
        sent a sample for them, the mean and minimum of fresh devices per frame, and how
        many frames had each count (``by_fresh``)."""
        if not self.frames:
            return {
                "frames": 0,
                "complete": 0,
                "complete_fraction": None,
                "fresh_mean": None,
                "fresh_min": None,
                "devices": 0,
                "by_fresh": {},
            }
        c = self._fresh
        return {
            "frames": self.frames,
            "complete": self._complete,
            "complete_fraction": self._complete / self.frames,
            "fresh_mean": sum(v * n for v, n in c.items()) / self.frames,
            "fresh_min": min(c),
            "devices": self._devices,
            "by_fresh": {str(k): c[k] for k in sorted(c)},
        }
