"""A simulated tracker failure happens once, counts down in its row, and Reset follows it."""

from __future__ import annotations

import pytest

pytestmark = pytest.mark.gui


def test_a_failure_happens_once_with_a_countdown_and_reset_follows_it(studio, qtbot):
    s, panel = studio.session, studio.sensor_panel
    joint = "lwrist" if "lwrist" in s.sensors else next(iter(s.sensors))
    row = panel.rows[joint]
    lost: list[int] = []  # frames drawn with the tracker lost

    def watch(frame):
        snap = s.latest
        if snap is not None and joint in snap.target_joints:
            if not snap.target_connected[snap.target_joints.index(joint)]:
                lost.append(frame)

    studio.snapshotDrawn.connect(watch)
    panel.fail_frames.setValue(20)
    s.seek(30)
    qtbot.waitUntil(lambda: s.latest.frame == 30, timeout=5000)
    stack_before = studio.undo.history.count()
    row["fail"].click()
    assert row["reset"].isEnabled()
    s.set_playback(loop=True)
    s.set_playing(True)
    texts = set()
    qtbot.waitUntil(lambda: texts.add(row["fail"].text()) or s.latest.frame >= 60, timeout=20000)
    assert any(t.startswith("Lost ") for t in texts), texts
    qtbot.waitUntil(lambda: not s.sensors[joint].failures, timeout=5000)
    assert row["fail"].text() == "Fail" and not row["reset"].isEnabled()
    assert studio.undo.history.count() == stack_before + 1, "running out is not an undo step"
    first = list(lost)
    assert first and min(first) >= 30 and max(first) < 50
    qtbot.waitUntil(lambda: s.latest.frame < 20, timeout=20000)  # looped
    qtbot.waitUntil(lambda: s.latest.frame >= 60, timeout=20000)
    assert lost == first, "the failure came back on the next loop"
