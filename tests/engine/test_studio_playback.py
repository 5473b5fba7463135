"""The playback clock (engine.studio.playback) on a fake monotonic clock: no thread, no sleeping."""

from __future__ import annotations

import pytest

from engine.studio import playback
from engine.studio.playback import ENDED, LOOPED, PlaybackClock


@pytest.fixture
def now(monkeypatch):
    """A settable stand-in for time.monotonic, seconds."""
    t = [100.0]
    monkeypatch.setattr(playback.time, "monotonic", lambda: t[0])
    return t


def test_every_frame_waits_for_the_solver_and_then_for_the_clock(now):
    clock = PlaybackClock(speed=1.0, pace="every_frame")
    clock.restart(10)
    assert clock.advance(10, last_solved=9, num_frames=100, fps=10) == (10, "")  # not solved yet
    assert clock.wait_time(10, last_solved=9, fps=10) == 0.0
    assert clock.advance(10, last_solved=10, num_frames=100, fps=10) == (10, "")  # not due yet
    assert clock.wait_time(10, last_solved=10, fps=10) == pytest.approx(0.1)
    now[0] += 0.1
    assert clock.advance(10, last_solved=10, num_frames=100, fps=10) == (11, "")
    assert clock.origin == (100.0, 10)  # on time: the clock keeps its origin


def test_every_frame_clock_waits_for_a_slow_solver_instead_of_skipping(now):
    clock = PlaybackClock(speed=2.0, pace="every_frame")
    clock.restart(0)
    now[0] += 5.0  # the solver took 5 s over frame 0
    assert clock.advance(0, last_solved=0, num_frames=100, fps=10) == (1, "")
    assert clock.origin == (105.0, 1)


def test_real_time_skips_frames_and_loops_or_ends(now):
    clock = PlaybackClock(speed=2.0, loop=True, pace="real_time")
    clock.restart(0)
    now[0] += 1.0
    assert clock.advance(0, last_solved=0, num_frames=100, fps=10) == (20, "")
    now[0] += 10.0
    assert clock.advance(20, last_solved=20, num_frames=100, fps=10) == (0, LOOPED)
    assert clock.origin == (now[0], 0)
    clock = PlaybackClock(speed=1.0, loop=False, pace="real_time", origin=(now[0], 95))
    now[0] += 1.0
    assert clock.advance(95, last_solved=95, num_frames=100, fps=10) == (99, ENDED)
