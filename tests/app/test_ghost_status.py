"""A ghost that cannot run with the current sensors says so once, in its own checkbox."""

from __future__ import annotations

import pytest

pytestmark = pytest.mark.gui


def test_a_ghost_that_cannot_run_says_why_once_in_its_row(studio, qtbot):
    s, panel = studio.session, studio.optimizer_panel
    studio.sensor_panel.preset.setCurrentText("3-head-hands")  # SparsePoser needs all six
    box = panel.ghost_boxes["sparseposer"]
    box.click()
    s.set_playing(True)
    qtbot.waitUntil(lambda: not box.isEnabled(), timeout=30000)
    assert "sparseposer" not in s.ghosts and not box.isChecked()
    assert "cannot run" in box.toolTip() and "6" in box.toolTip()
    start = s.latest.frame
    qtbot.waitUntil(lambda: s.latest.frame > start + 20, timeout=20000)
    told = [m for m in s.latest.recent_errors if m.startswith("sparseposer")]
    assert len(told) == 1, told
    assert "sparseposer" not in studio.statusBar().currentMessage()
    studio.sensor_panel.preset.setCurrentText("6")
    assert box.isEnabled() and "cannot run" not in box.toolTip()


def test_a_ghost_failing_on_every_frame_is_reported_once(studio, qtbot):
    """The engine side alone: the ghost stays ticked and fails on every frame."""
    s = studio.session
    studio.ghost_status.on_snapshot = lambda snap: None  # leave the ghost ticked
    studio.sensor_panel.preset.setCurrentText("3-head-hands")
    s.set_ghosts(("sparseposer",))
    s.set_playing(True)
    qtbot.waitUntil(lambda: any(m.startswith("sparseposer") for m in s.latest.recent_errors), timeout=30000)
    start = s.latest.frame
    qtbot.waitUntil(lambda: s.latest.frame > start + 20, timeout=20000)
    assert sum(m.startswith("sparseposer") for m in s.latest.recent_errors) == 1
