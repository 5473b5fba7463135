"""Edit > Settle pose (Ctrl+Return) runs on a worker: the pose window keeps answering
while it solves, and the result is applied on the GUI thread as one undo step."""

from __future__ import annotations

import threading
import time

import numpy as np
import pytest
from PyQt6.QtCore import Qt, QTimer
from PyQt6.QtTest import QTest
from PyQt6.QtWidgets import QApplication

from engine import skeleton as sk

pytestmark = pytest.mark.gui


@pytest.mark.slow  # two settles of the pose, ~5 s
def test_settle_runs_off_the_gui_thread_and_applies_one_undo_step(pose_window, qtbot):
    w = pose_window
    wrist = w.mode.pose.positions[sk.JOINT_INDEX["lwrist"]].copy()
    w.drag_joint("lwrist", wrist + [0.25, -0.2, 0.35])
    expected = w.mode.detached()
    expected.settle()  # what the settle must give, solved here beforehand
    steps = w.undo.count()
    applied: list[threading.Thread] = []
    w.session.events.pose.connect(lambda e: applied.append(threading.current_thread()))
    ticks: list[float] = []
    timer = QTimer(interval=10)
    timer.timeout.connect(lambda: ticks.append(time.perf_counter()))
    timer.start()
    w.windowHandle().requestActivate()
    qtbot.waitUntil(lambda: QApplication.activeWindow() is w)
    QTest.keyClick(w, Qt.Key.Key_Return, Qt.KeyboardModifier.ControlModifier)
    worker = w.jobs.thread
    assert worker is not None and worker is not threading.main_thread(), "the settle ran on the GUI thread"
    with qtbot.waitSignal(w.jobs.finished, timeout=60000) as done:
        pass
    timer.stop()
    assert done.args == [True, ""]
    assert applied and all(t is threading.main_thread() for t in applied)  # applied on the GUI thread
    assert np.allclose(w.mode.pose.positions, expected.pose.positions, atol=1e-6)
    assert w.undo.count() == steps + 1
    gaps = np.diff(ticks) * 1000.0
    assert len(ticks) > 5 and np.percentile(gaps, 99) < 250.0, (len(ticks), np.percentile(gaps, 99))
    w.undo.undo()
    assert not np.allclose(w.mode.pose.positions, expected.pose.positions, atol=1e-4)


def test_a_pose_changed_while_it_settled_is_kept(pose_window, qtbot):
    w = pose_window
    wrist = w.mode.pose.positions[sk.JOINT_INDEX["lwrist"]].copy()
    w.drag_joint("lwrist", wrist + [0.2, 0.0, 0.3])
    job = w.session.settle_job()
    w.session.drag_joint("lwrist", wrist + [0.1, 0.0, 0.1])  # an edit meanwhile (undo, a script)
    moved = w.mode.pose.positions.copy()
    from engine.errors import UserError

    with pytest.raises(UserError, match="changed while it settled"):
        w.session.take_settle(job, job.run())
    assert np.array_equal(w.mode.pose.positions, moved)
