"""Cycles are collected on the GUI thread between events (app.collector), never inside a
paint: a window with a plot, dropped while its paint was pending and collected inside
that paint, segfaulted in ``QPainter`` (docs/reliability.md, the test-order crash)."""

from __future__ import annotations

import gc
import os
import subprocess
import sys
import weakref

from PyQt6.QtWidgets import QWidget

from app.collector import collected_between_events
from tests.conftest import REPO


def test_windows_dropped_before_their_paint_do_not_crash_the_application():
    # 20 windows: with Python's automatic collection the same child segfaulted in each of
    # four runs (Qt: "Cannot destroy paint device that is being painted")
    env = {**os.environ, "PYTHONPATH": str(REPO)}
    done = subprocess.run(
        [sys.executable, "-m", "tests.app.collector_child", "between", "20"],
        cwd=REPO,
        env=env,
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert done.returncode == 0 and "survived" in done.stdout, done.stderr[-2000:]


def test_the_collector_runs_from_the_event_loop_and_restores_automatic_collection(qtbot):
    was = gc.isenabled()
    with collected_between_events(0.01):
        assert not gc.isenabled()
        w = QWidget()
        w.itself = w  # a cycle
        gone = weakref.ref(w)
        del w
        # past the youngest generation's threshold (kept: freeing them would lower the count again)
        made = [[] for _ in range(2 * gc.get_threshold()[0])]
        qtbot.waitUntil(lambda: gone() is None, timeout=5000)
        del made
    assert gc.isenabled() == was
