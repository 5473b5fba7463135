"""Edit ▸ Re-solve range in the studio: the clip's range replaced, undo restores it."""

from __future__ import annotations

import numpy as np
import pytest

pytestmark = pytest.mark.gui


def test_resolving_a_range_replaces_it_and_undo_redo_round_trip(studio, qtbot):
    from app.range_actions import resolve_range

    session = studio.session
    original = session.motion
    before = original.local_rot.copy()
    session.seek(40)
    edit = resolve_range(studio, 30, 50, blend=4).wait()
    assert session.motion is edit.motion and session.frame == 40
    assert np.array_equal(session.motion.local_rot[: edit.first], before[: edit.first])
    assert np.array_equal(session.motion.local_rot[edit.last + 1 :], before[edit.last + 1 :])
    assert not np.array_equal(session.motion.local_rot[30:51], before[30:51])
    assert "resolve_range" in studio.actions_by_name and studio.undo.history.count() == 1
    studio.undo.history.undo()
    assert session.motion is original and np.array_equal(session.motion.local_rot, before)
    studio.undo.history.redo()
    assert session.motion is edit.motion
    qtbot.waitUntil(lambda: session.latest is not None, timeout=10000)


def test_a_range_resolve_runs_off_the_gui_thread_and_cancel_leaves_the_clip(studio, qtbot):
    """The event loop goes on while the worker solves (a 10 ms timer keeps firing) and
    Cancel stops it: the clip, the undo history and the frame are as they were."""
    import threading
    import time

    from PyQt6.QtCore import QTimer
    from PyQt6.QtWidgets import QPushButton

    from app.range_actions import resolve_range

    session = studio.session
    original = session.motion
    ticks: list[float] = []
    timer = QTimer(interval=10)
    timer.timeout.connect(lambda: ticks.append(time.perf_counter()))
    timer.start()
    runner = resolve_range(studio, 0, len(original) - 1, blend=0)
    worker = runner.thread
    assert worker is not None and worker is not threading.main_thread() and worker.is_alive()
    # frames solved while the loop ran; then the timer's ticks while the worker solves (the
    # start, where the worker may load the models, is not the claim)
    qtbot.waitUntil(lambda: runner.done >= 3, timeout=60000)
    solving = len(ticks)
    qtbot.waitUntil(lambda: len(ticks) > solving + 30, timeout=60000)
    assert runner.running and runner.dialog is not None and runner.dialog.maximum() == len(original)
    gaps = np.diff(ticks[solving:]) * 1000.0
    assert np.percentile(gaps, 99) < 250.0, (len(gaps), np.percentile(gaps, 99))
    with qtbot.waitSignal(runner.finished, timeout=30000) as done:
        runner.dialog.findChild(QPushButton).click()  # the dialog's Cancel button
    timer.stop()
    assert done.args == [False, "cancelled"] and runner.result is None and not worker.is_alive()
    assert session.motion is original and studio.undo.history.count() == 0
    assert "cancelled" in studio.statusBar().currentMessage()


def test_a_range_resolve_keeps_the_camera_on_the_frame_on_screen(studio, qtbot):
    """The re-solved clip is the same clip: the camera the user set stays, centred on the
    frame on screen (not moved to frame 0's hips, which left the character near and
    off-centre on a paused frame)."""
    from PyQt6.QtCore import Qt
    from PyQt6.QtTest import QTest
    from PyQt6.QtWidgets import QApplication

    from app.range_actions import resolve_range

    session, view = studio.session, studio.viewport
    session.seek(100)
    qtbot.waitUntil(lambda: session.latest.frame == 100, timeout=30000)
    studio.windowHandle().requestActivate()
    qtbot.waitUntil(lambda: QApplication.activeWindow() is studio)
    studio.timeline.slider.setFocus()
    QTest.keyClick(QApplication.focusWidget(), Qt.Key.Key_3)  # the side view, as a user sets it
    assert view.camera_preset == "side"
    cam = view.plotter.camera
    offset = np.subtract(cam.position, cam.focal_point)
    seq = session.latest.seq
    resolve_range(studio, 90, 110, blend=4).wait()
    qtbot.waitUntil(lambda: session.latest.seq > seq and session.latest.frame == 100, timeout=30000)
    qtbot.waitUntil(lambda: studio.drawing._drawn_seq == session.latest.seq, timeout=10000)
    assert np.allclose(np.subtract(cam.position, cam.focal_point), offset, atol=1e-6)
    hips = session.latest.positions[0]
    assert np.allclose(cam.focal_point[:2], hips[:2], atol=0.05)
