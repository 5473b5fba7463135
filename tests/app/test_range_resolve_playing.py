"""A range re-solved while the clip plays and paused before it ends: afterwards the
timeline, the session and the engine's snapshots agree on the frame."""

from __future__ import annotations

import pytest

pytestmark = pytest.mark.gui


def test_a_pause_while_the_range_is_resolved_is_the_frame_kept(studio, qtbot):
    from app.range_actions import resolve_range

    session = studio.session
    session.play()
    qtbot.waitUntil(lambda: session.latest is not None and session.latest.playing and session.latest.frame > 20)
    runner = resolve_range(studio, 5, 15, blend=2)
    session.pause()
    runner.wait()
    qtbot.wait(1500)
    snap = session.latest
    assert not snap.playing
    assert session.frame == snap.frame, (session.frame, snap.frame)
    assert studio.timeline.slider.value() == snap.frame, (studio.timeline.slider.value(), snap.frame)
