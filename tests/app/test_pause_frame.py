"""A pause stops on one frame that the timeline, the 3D view and the latent readouts all
name: the engine solves a few frames past the timeline's last update before the pause
reaches it, and the timeline takes the frame the engine stopped on."""

from __future__ import annotations

import pytest
from PyQt6.QtCore import Qt
from PyQt6.QtGui import QAction

pytestmark = pytest.mark.gui


def test_pause_shows_the_frame_the_engine_stopped_on(studio, qtbot):
    s = studio.session
    drawn: list[int] = []
    studio.snapshotDrawn.connect(drawn.append)
    s.play()
    qtbot.waitUntil(lambda: s.frame >= 10, timeout=20000)
    # the engine is ahead of the timeline (it updates the timeline 10 times a second)
    qtbot.waitUntil(lambda: s.latest.playing and s.latest.frame > s.frame, timeout=20000)
    button = studio.timeline.play_button
    qtbot.mouseClick(button, Qt.MouseButton.LeftButton)
    assert not s.playing
    qtbot.waitUntil(lambda: not s.latest.playing and bool(drawn) and drawn[-1] == s.latest.frame, timeout=10000)
    qtbot.wait(300)  # the timeline's panel has had its turns
    stopped = s.latest.frame
    assert s.frame == stopped
    assert studio.timeline.counter.text().startswith(f"{stopped} /")


@pytest.mark.parametrize("delta", [1, -1])
def test_step_while_playing_steps_from_the_frame_on_screen(studio, qtbot, delta):
    s = studio.session
    s.play()
    qtbot.waitUntil(lambda: s.frame >= 10, timeout=20000)
    qtbot.waitUntil(lambda: s.latest.playing and s.latest.frame > s.frame + 1, timeout=20000)
    shown = s.latest.frame
    name = "Next frame" if delta > 0 else "Previous frame"
    (entry,) = [a for a in studio.findChildren(QAction) if a.text().replace("&", "") == name]
    entry.trigger()  # Playback > Next / Previous frame (Right / Left)
    assert not s.playing
    assert s.frame in (shown + delta, shown + 1 + delta), "the engine may have drawn one more frame meanwhile"
    qtbot.waitUntil(lambda: not s.latest.playing and s.latest.frame == s.frame, timeout=10000)
    assert studio.timeline.counter.text().startswith(f"{s.frame} /")
