"""Edits while paused: the frame on screen is solved again from the state it had before
the edit, so taking an edit back gives the pose back."""

from __future__ import annotations

import numpy as np
import pytest

from engine import skeleton as sk

pytestmark = pytest.mark.gui


def _resolved(studio, qtbot, seq: int):
    qtbot.waitUntil(lambda: studio.session.latest.seq > seq, timeout=30000)
    return studio.session.latest


@pytest.mark.slow
def test_removing_a_dragged_pin_while_paused_gives_the_pose_back(studio, qtbot):
    s = studio.session
    s.set_method("dragposer")
    qtbot.waitUntil(lambda: s.latest.method == "dragposer" and bool(s.latest.losses), timeout=60000)
    s.set_playing(True)
    qtbot.waitUntil(lambda: s.latest.frame >= 20, timeout=60000)
    s.pause()
    qtbot.waitUntil(lambda: not s.latest.playing, timeout=10000)
    seq = s.latest.seq
    shown = s.latest.frame
    s.seek(shown)  # the frame solved again with nothing edited: what removing the pin must give
    before = _resolved(studio, qtbot, seq)
    assert before.frame == shown
    knee = before.positions[sk.JOINT_INDEX["lknee"]].copy()
    for dx in np.linspace(0.02, 0.2, 10):  # a Ctrl-drag of the knee, 20 cm sideways
        seq = s.latest.seq
        studio.viewport.jointDragged.emit("lknee", knee + [dx, 0.0, 0.0])
        _resolved(studio, qtbot, seq)
    pinned = s.latest
    assert np.linalg.norm(pinned.positions[sk.JOINT_INDEX["lknee"]] - knee) > 0.05  # the pin did pull
    seq = s.latest.seq
    s.constraints.remove("pin lknee")
    after = _resolved(studio, qtbot, seq)
    assert after.frame == before.frame
    error = np.linalg.norm(after.positions - before.positions, axis=1)
    assert error.max() < 1e-3, f"the pose did not come back: {error.max() * 100:.1f} cm off"
    assert np.abs(after.latent).max() < np.abs(before.latent).max() + 1.0
