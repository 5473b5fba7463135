"""Closing a window leaves no worker in torch: a Python thread still inside torch when
the interpreter finalizes is unwound through C++ and the process aborts (*terminate
called without an active exception*, three of thirteen seed-6 monkey runs). The studio's
engine thread with inspections queued and the pose window's settle are started through
the real windows, the windows closed, and no worker may outlive the close."""

from __future__ import annotations

import threading
import time

import pytest
from PyQt6.QtCore import QSettings, Qt
from PyQt6.QtWidgets import QApplication

from engine import skeleton as sk

#: a DragPoser studio solving its first frames, then a settle: ~30 s on a loaded 2-core machine
pytestmark = [pytest.mark.gui, pytest.mark.slow]


def _alive(name: str) -> list[threading.Thread]:
    return [t for t in threading.enumerate() if t.name == name and t.is_alive()]


def test_closing_the_studio_during_inspections_stops_the_engine_thread(qtbot, tmp_path, synthetic_motion):
    from app.main_window import MainWindow

    window = MainWindow(
        method="dragposer",
        settings=QSettings(str(tmp_path / "studio.ini"), QSettings.Format.IniFormat),
        engine="thread",
    )
    window.session.set_motion(synthetic_motion)
    window.resize(1280, 800)
    window.show()
    s = window.session
    qtbot.waitUntil(lambda: s.latest is not None and s.latest.latent_view is not None, timeout=120000)
    s.pause()
    views = window.latent_views
    views.dock.raise_()
    views.tabs.setCurrentIndex(1)  # the Forces tab
    QApplication.processEvents()
    engine = window.engine
    # each click queues an inspection of several seconds' torch work
    for _ in range(10):
        qtbot.mouseClick(views.forces.inspect_button, Qt.MouseButton.LeftButton)
    qtbot.wait(300)  # the first one under way
    window.undo.set_clean()
    window.close()
    QApplication.processEvents()
    assert not engine.is_alive(), "the engine thread outlived the studio"
    assert not _alive("dragposer-engine")
    window.deleteLater()


def test_closing_the_pose_window_during_a_settle_stops_its_worker(pose_window, qtbot):
    w = pose_window
    # a wrist target out of reach: every one of the settle's rounds runs (seconds each)
    w.mode.options.settle_rounds = 100
    wrist = w.mode.pose.positions[sk.JOINT_INDEX["lwrist"]].copy()
    w.drag_joint("lwrist", wrist + [1.5, 0.0, 0.5])
    runner = w.settle()
    worker = runner.thread
    assert worker is not None and worker.is_alive()
    time.sleep(0.5)  # into the settle's torch work
    w.session.history.set_clean()
    t0 = time.monotonic()
    w.close()
    took = time.monotonic() - t0
    assert not worker.is_alive(), f"the settle's worker outlived the pose window ({took:.1f} s closing)"
    assert not _alive("authoring-job")
    assert runner.thread is None and runner.message == "cancelled"
