"""A live run's figures stay the same size however long the stream runs, and summarise
the whole run as numpy would from every frame's values."""

from __future__ import annotations

import time
import tracemalloc
from collections import Counter

import numpy as np
import pytest

from engine import skeleton as sk
from engine.methods import FrameResult, Method
from engine.sensors import Sensor, SensorFrame
from engine.tracker_io import live, live_figures
from engine.tracker_io.live import LiveRun
from engine.tracker_io.live_figures import RECENT_FRAMES, FrameFigures, LogHistogram, percentile_of_counts
from engine.tracker_io.receiver import LiveFrame


def _fill(n: int, recent: int, seed: int = 0) -> tuple[FrameFigures, dict[str, np.ndarray]]:
    rng = np.random.default_rng(seed)
    values = {
        "latency": rng.lognormal(np.log(9.0), 0.4, n),  # ms, skewed as a stream's are
        "solve": rng.lognormal(np.log(4.0), 0.3, n),
        "iterations": rng.integers(1, 11, n),
        "fresh": rng.choice([3, 5, 6], n, p=[0.05, 0.15, 0.8]),
        "devices": np.full(n, 6),
    }
    fig = FrameFigures(recent)
    for k in range(n):
        lat, solve, iters, fresh = (values[a][k] for a in ("latency", "solve", "iterations", "fresh"))
        fig.add(float(lat), float(solve), int(iters), int(fresh), 6)
    return fig, values


def test_the_summaries_are_exact_while_the_run_fits_the_recent_window():
    fig, v = _fill(80, recent=100)
    lat = fig.latency_summary()
    assert lat["p50"] == pytest.approx(np.percentile(v["latency"], 50), rel=1e-12)
    assert lat["p95"] == pytest.approx(np.percentile(v["latency"], 95), rel=1e-12)
    assert fig.solve_median_ms() == pytest.approx(np.median(v["solve"]), rel=1e-12)


def test_a_run_longer_than_the_window_is_summarised_within_half_a_bin():
    fig, v = _fill(20000, recent=100)
    assert fig.frames == 20000 and len(fig.latency_ms) == len(fig.fresh) == 100
    assert list(fig.latency_ms) == pytest.approx(v["latency"][-100:])  # the newest, in order
    lat = fig.latency_summary()
    assert lat["p50"] == pytest.approx(np.percentile(v["latency"], 50), rel=0.006)
    assert lat["p95"] == pytest.approx(np.percentile(v["latency"], 95), rel=0.006)
    assert lat["max"] == v["latency"].max()
    assert fig.solve_median_ms() == pytest.approx(np.median(v["solve"]), rel=0.006)
    # counted figures are exact whatever the length
    it = fig.iteration_summary()
    assert it["median"] == np.median(v["iterations"]) and it["p5"] == np.percentile(v["iterations"], 5)
    assert it["mean"] == pytest.approx(v["iterations"].mean()) and it["min"] == v["iterations"].min()
    c = fig.completeness_summary()
    assert c["frames"] == 20000 and c["complete"] == int(np.sum(v["fresh"] >= 6))
    assert c["fresh_mean"] == pytest.approx(v["fresh"].mean()) and c["fresh_min"] == 3 and c["devices"] == 6
    assert c["by_fresh"] == {str(k): int(n) for k, n in zip(*np.unique(v["fresh"], return_counts=True))}


def test_completeness_counts_frames_by_fresh_devices():
    fig = FrameFigures()
    for fresh in (6, 5, 6, 6, 3):
        fig.add(1.0, 1.0, 1, fresh, 6)
    c = fig.completeness_summary()
    assert (c["frames"], c["complete"], c["fresh_min"], c["devices"]) == (5, 3, 3, 6)
    assert c["complete_fraction"] == pytest.approx(0.6) and c["fresh_mean"] == pytest.approx(5.2)
    assert c["by_fresh"] == {"3": 1, "5": 1, "6": 3}
    empty = FrameFigures()
    assert empty.completeness_summary()["complete_fraction"] is None
    assert empty.latency_summary()["p50"] is None and empty.iteration_summary()["median"] is None


@pytest.mark.parametrize("q", [0, 5, 37.5, 50, 95, 100])
def test_percentile_of_counts_is_numpys_on_the_expanded_values(q):
    values = np.random.default_rng(1).integers(0, 40, 997)
    assert percentile_of_counts(Counter(values.tolist()), q) == pytest.approx(np.percentile(values, q), abs=1e-12)


def test_the_histogram_keeps_values_outside_its_range_and_its_size():
    h = LogHistogram()
    size = h.counts.size
    for value in (0.0, 1e-9, 5.0, 1e9):
        h.add(value)
    assert h.counts.size == size and h.count == 4 and h.counts.sum() == 4
    assert h.percentile(0) == 0.0 and h.percentile(100) == 1e9  # the exact extremes
    assert h.percentile(50) == pytest.approx(1e-3, rel=0.01)  # rank 1 of 0..3: the first bin
    assert np.isnan(LogHistogram().percentile(50))


class _Stream:
    """``n`` frames, each arriving as it is asked for, then silence."""

    def __init__(self, n: int) -> None:
        self.n, self.last_arrival = n, None
        self.sensors = SensorFrame(0, {"root": Sensor("root", np.zeros(3))})

    def wait_frame(self, after: int, timeout: float) -> LiveFrame | None:
        if after < self.n:
            return LiveFrame(after + 1, after / 60.0, time.perf_counter(), self.sensors, 6, 6)
        self.last_arrival = time.perf_counter() - 10.0
        return None


class _Still(Method):
    name = "still"

    def __init__(self) -> None:
        self.pose = FrameResult(
            np.tile([1.0, 0, 0, 0], (sk.NUM_JOINTS, 1)), np.zeros(3), np.zeros((sk.NUM_JOINTS, 3)), 3
        )

    def reset(self, skeleton: sk.Skeleton, fps: float = sk.FPS, *, reference: object = None) -> None:
        pass

    def step(self, sensors: SensorFrame) -> FrameResult:
        return self.pose


def test_a_long_live_run_that_keeps_no_frames_does_not_grow():
    """A stream of an hour solves 216,000 frames: what the run keeps of them (traced
    allocations of the live modules) must not grow past the recent window."""
    n = RECENT_FRAMES + 12000
    start = RECENT_FRAMES + 500
    traced: dict[int, int] = {}
    files = [tracemalloc.Filter(True, live.__file__), tracemalloc.Filter(True, live_figures.__file__)]

    def on_frame(result: live.LiveResult) -> None:
        if result.frames_solved in (start, n):
            snapshot = tracemalloc.take_snapshot().filter_traces(files)
            traced[result.frames_solved] = sum(s.size for s in snapshot.statistics("filename"))

    run = LiveRun(_Stream(n), _Still(), sk.Skeleton.canonical(), 60.0, keep_frames=False)  # type: ignore[arg-type]
    tracemalloc.start()
    try:
        out = run.run(idle_timeout_s=1.0, on_frame=on_frame)
    finally:
        tracemalloc.stop()
    assert out.frames_solved == n and out.results == []
    # a list per figure grew by about 120 bytes a frame: 1.4 MB over these 11,500 frames
    assert traced[n] - traced[start] < 32_000, traced
