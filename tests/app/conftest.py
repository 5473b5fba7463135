"""The ``studio`` fixture: a main window on a synthetic clip that must clean up after itself
(no thread, VTK interactor or visible window may outlive a test); ``pose_window``: a pose
and key window on a 1.75 m character (``vae``: the shipped pose VAE, loaded once);
``keyed``: that window with keys at frames 0 and 40 made by real clicks and a drag."""

from __future__ import annotations

import threading

import pytest


@pytest.fixture
def studio(qtbot, tmp_path, synthetic_motion, monkeypatch):
    from PyQt6.QtCore import QEvent, QSettings
    from PyQt6.QtWidgets import QApplication, QMessageBox

    from app.main_window import MainWindow

    # A modal message box would block the test forever: record it instead and fail the
    # test at teardown. Tests that expect a dialog patch QMessageBox themselves.
    unexpected: list[str] = []
    for name in ("critical", "warning", "information", "question"):
        monkeypatch.setattr(QMessageBox, name, lambda *a, _n=name, **k: unexpected.append(f"{_n}: {a[1:3]}"))

    threads_before = set(threading.enumerate())
    settings = QSettings(str(tmp_path / "studio.ini"), QSettings.Format.IniFormat)
    window = MainWindow(settings=settings, engine="thread")  # tests reach into the engine
    window.files.ask_constraints = lambda _w, names, clip: unexpected.append(f"constraints: {names}") or "keep"
    window.session.set_motion(synthetic_motion)
    window.resize(1280, 800)
    window.show()
    qtbot.waitUntil(lambda: window.session.latest is not None, timeout=10000)
    yield window
    window.undo.set_clean()  # edits are discarded unasked (tests of the prompt answer it themselves)
    window.close()
    assert not unexpected, f"unexpected message boxes: {unexpected}"
    QApplication.processEvents()
    assert not window.engine.is_alive(), "engine thread outlived the window"
    # threads this test started and left running; one of an earlier test may end meanwhile
    leaked_threads = [t.name for t in threading.enumerate() if t not in threads_before]
    assert not leaked_threads, f"threads leaked: {leaked_threads}"
    assert window.viewport.plotter._closed, "the VTK interactor outlived the window"
    window.deleteLater()
    QApplication.sendPostedEvents(None, QEvent.Type.DeferredDelete.value)
    leaked = [type(w).__name__ for w in QApplication.topLevelWidgets() if w.isVisible()]
    assert not leaked, f"widgets left open: {leaked}"


@pytest.fixture(scope="session")
def vae():
    from engine.models import load_default_models

    return load_default_models().vae


@pytest.fixture
def pose_window(qtbot, vae, monkeypatch, tmp_path):
    from PyQt6.QtCore import QSettings
    from PyQt6.QtWidgets import QMessageBox

    from app.pose_window import PoseWindow
    from engine.authoring.pose_mode import PoseMode
    from engine.authoring.session import AuthoringSession
    from tests.app.gui_helpers import close_now

    monkeypatch.setattr(QMessageBox, "question", lambda *a, **k: QMessageBox.StandardButton.Discard)
    # the window's own settings: what one test remembers (a save folder) is not the next one's
    settings = QSettings(str(tmp_path / "pose.ini"), QSettings.Format.IniFormat)
    w = PoseWindow(AuthoringSession(PoseMode(vae, 1.75)), settings=settings)
    w.resize(1000, 700)
    w.show()
    yield w
    close_now(w)


@pytest.fixture
def keyed(pose_window, qtbot):
    """The pose window with keys at frames 0 (no target) and 40 (the left wrist raised by a
    drag: a target only that key has), in the front view, at frame 40."""
    from PyQt6.QtWidgets import QApplication

    from tests.app.gui_helpers import drag_wrist, scrub

    w = pose_window
    w.activateWindow()
    qtbot.waitUntil(lambda: QApplication.activeWindow() is w)
    w.actions_by_name["camera-front"].trigger()
    w.keys.add.click()
    scrub(w, 40)
    drag_wrist(w)
    w.keys.add.click()
    assert [k.frame for k in w.scene.keys] == [0, 40]
    return w
