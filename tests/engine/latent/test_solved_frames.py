"""The store of solved frames the studio's latent views share: it outlives the engine's
history restarts, the newest solve of a frame wins, and an earlier flagged solve is kept."""

from __future__ import annotations

import pickle
from types import SimpleNamespace

import numpy as np

from engine.latent.solved_frames import SolvedFrames


def entry(frame: int, nearest: float = 1.0, flagged: bool = False, ms: float = 2.0):
    r = {"x": 0.1 * frame, "y": -0.1 * frame, "nearest": nearest, "norm": 3.0, "predictor": 0.5}
    return SimpleNamespace(frame=frame, ms=ms, iterations=5, readouts={**r, "flagged": float(flagged)})


def test_frames_survive_a_history_restart_and_the_newest_solve_wins():
    s = SolvedFrames()
    assert s.note([entry(f, flagged=f == 6) for f in range(10)])
    assert list(s.frames) == list(range(10)) and s.flagged_frames == [6]
    assert s.next_flagged(2) == 6 and s.next_flagged(7) == 6  # wraps
    # a seek back: the engine's history restarts with frame 6 solved again, unflagged
    assert s.note([entry(6, nearest=0.7, ms=9.0)])
    assert len(s) == 10 and s.flagged_frames == [] and s.next_flagged(0) is None
    assert s.row(6)["nearest"] == 0.7
    assert s.earlier_flag(6) == {**entry(6).readouts, "flagged": 1.0}
    assert s.xy.shape == (10, 2) and np.allclose(s.xy[3], [0.3, -0.3])
    s.clear()
    assert len(s) == 0 and s.frames.shape == (0,) and s.earlier_flag(6) is None


def test_only_new_entries_are_read_even_unpickled():
    s = SolvedFrames()
    history = [entry(f) for f in range(5)]
    s.note(history)
    version = s.version
    assert not s.note(pickle.loads(pickle.dumps(history)))  # the same solves, new objects
    assert s.version == version
    assert s.note(history + [entry(5)]) and list(s.frames) == list(range(6))
