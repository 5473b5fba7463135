"""The studio's solver process killed under it (app/engine_watch.py): one line says so, a
new process carries on with the same clip, method, sensors, constraints and frame; the
third death within a minute is not restarted and the window says why."""

from __future__ import annotations

import os
import signal
import threading

import pytest

pytestmark = [pytest.mark.gui, pytest.mark.slow]

#: A spawned engine imports torch and loads its method first: slow on a loaded 2-core machine.
START_MS = 120000


@pytest.fixture
def process_studio(qtbot, tmp_path, synthetic_motion, monkeypatch):
    from PyQt6.QtCore import QEvent, QSettings
    from PyQt6.QtWidgets import QApplication, QMessageBox

    from app.main_window import MainWindow

    errors: list[str] = []
    monkeypatch.setattr(QMessageBox, "critical", lambda *a, **k: errors.append(f"{a[1]}: {a[2]}"))
    threads_before = set(threading.enumerate())
    window = MainWindow(settings=QSettings(str(tmp_path / "studio.ini"), QSettings.Format.IniFormat), engine="process")
    window.errors = errors
    window.session.set_motion(synthetic_motion)
    window.show()
    qtbot.waitUntil(lambda: window.session.latest is not None, timeout=START_MS)
    yield window
    window.undo.set_clean()
    window.close()
    QApplication.processEvents()
    assert not window.engine.is_alive(), "the engine outlived the window"
    # threads this test started and left running; one of an earlier test may end meanwhile
    leaked_threads = [t.name for t in threading.enumerate() if t not in threads_before]
    assert not leaked_threads, f"threads leaked: {leaked_threads}"
    window.deleteLater()
    QApplication.sendPostedEvents(None, QEvent.Type.DeferredDelete.value)


def kill(engine) -> None:
    os.kill(engine._process.pid, signal.SIGKILL)


def test_a_killed_solver_is_restarted_with_the_same_session_and_the_third_death_is_not(process_studio, qtbot):
    w = process_studio
    s = w.session
    s.pause()
    s.sensors.set_preset("4")
    s.constraints.add("pin", joint="lwrist", position=(0.3, 0.2, 1.0))
    s.seek(25)
    first = w.engine
    qtbot.waitUntil(lambda: s.latest.frame == 25 and len(s.latest.target_joints) == 4, timeout=30000)
    kill(first)
    qtbot.waitUntil(lambda: w.engine is not first, timeout=10000)
    line = w.statusBar().currentMessage()
    assert line.startswith(
        "The solver stopped (the engine process stopped unexpectedly (exit code -9)); restarted it on frame 25"
    ), line
    assert "\n" not in line and not w.errors
    s.seek(27)  # an edit while the new engine starts
    second = w.engine
    qtbot.waitUntil(lambda: s.latest is not None and s.latest.frame == 27, timeout=START_MS)
    snap = s.latest
    assert set(snap.target_joints) == set(s.sensors) and len(snap.target_joints) == 4
    assert any(name == "pin" for name, _ in snap.gizmos) and snap.method == s.method
    qtbot.waitUntil(lambda: not w.busy.active, timeout=10000)  # the loading notice is gone

    kill(second)
    qtbot.waitUntil(lambda: w.engine is not second, timeout=10000)
    third = w.engine
    qtbot.waitUntil(lambda: s.latest is not None, timeout=START_MS)
    kill(third)
    qtbot.waitUntil(lambda: bool(w.errors), timeout=10000)
    assert w.engine is third and w.drawing.engine_watch.restarts == 2
    assert w.errors == [
        "The engine stopped: The solver stopped (the engine process stopped unexpectedly (exit code -9)): the "
        "solver process stopped 3 times within 60 s, so it is not restarted again.\n\nYour edits are kept: save "
        "the scene (File > Save scene) and start the studio again."
    ]
    assert w.statusBar().currentMessage().endswith("so it is not restarted again")
