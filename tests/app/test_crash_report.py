"""No silent exit: a process that dies of a fatal signal leaves a crash report with its
stacks and its last input, the next start offers it once, a clean exit leaves nothing,
and an exception no slot caught is logged and shown instead of ending the process."""

from __future__ import annotations

import faulthandler
import os
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest
from PyQt6.QtWidgets import QMessageBox

from app.crash_report import CrashLog, left_reports, offer

REPO = Path(__file__).resolve().parents[2]

CRASHING = textwrap.dedent("""
    import faulthandler, sys
    from pathlib import Path
    from PyQt6.QtCore import Qt
    from PyQt6.QtTest import QTest
    from PyQt6.QtWidgets import QApplication, QLineEdit
    from app.crash_report import CrashLog
    app = QApplication([])
    log = CrashLog(Path(sys.argv[1]))
    log.start()
    field = QLineEdit()
    field.setObjectName("height")
    QTest.keyClick(field, Qt.Key.Key_3)
    faulthandler._sigsegv()
""")


def test_a_segfault_leaves_a_report_that_the_next_start_offers_once(tmp_path, qtbot):
    env = {**os.environ, "QT_QPA_PLATFORM": "offscreen", "PYTHONPATH": str(REPO)}
    run = subprocess.run(
        [sys.executable, "-c", CRASHING, str(tmp_path)], env=env, capture_output=True, text=True, timeout=120
    )
    assert run.returncode != 0
    (log,) = tmp_path.glob("crash-*.log")
    text = log.read_text()
    assert "Fatal Python error: Segmentation fault" in text and "<string>" in text  # the Python stack
    assert "DragPoser Studio, pid" in text and "Python 3" in text
    assert "key 0x33 '3' mods 0x0 on QLineEdit(height)" in text  # the last input
    reports = left_reports(tmp_path)
    assert [p.name for p in reports] == [log.name.replace(".log", ".reported.log")]
    box = offer(None, reports)
    qtbot.addWidget(box)
    assert "crashed" in box.text() and str(reports[0]) in box.informativeText()
    assert "Segmentation fault" in box.detailedText()
    assert left_reports(tmp_path) == []  # offered once
    assert offer(None, []) is None


def test_a_clean_exit_leaves_no_report(tmp_path, qtbot):
    log = CrashLog(tmp_path)
    log.start()
    try:
        assert log.path.is_file() and log.path.name == f"crash-{os.getpid()}.log"
        for k in range(500):  # older input is dropped, the log stays short
            log.note(f"input {k}")
        text = log.path.read_text()
        assert "input 499" in text and "input 0\n" not in text and text.count("\n") < 450
        assert left_reports(tmp_path) == []  # this process's own log is not a crash
    finally:
        log.close()
    assert list(tmp_path.iterdir()) == []
    assert faulthandler.is_enabled()  # pytest's own handler is back


def test_an_exception_nothing_caught_is_logged_and_shown(tmp_path, monkeypatch):
    shown = []
    monkeypatch.setattr(QMessageBox, "critical", lambda *a, **k: shown.append(a[2]))
    log = CrashLog(tmp_path)
    log.start()
    try:
        try:
            raise ValueError("bad slot")
        except ValueError as exc:
            sys.excepthook(type(exc), exc, exc.__traceback__)
        text = log.path.read_text()
        assert "uncaught exception" in text and "ValueError: bad slot" in text
        assert shown and "bad slot" in shown[0] and str(log.path) in shown[0]
    finally:
        log.close()
    assert sys.excepthook is not log.excepthook


@pytest.mark.parametrize("name", ["crash-1.log.bak", "crash-x.log", "notes.log"])
def test_other_files_are_not_reports(tmp_path, name):
    (tmp_path / name).write_text("x")
    assert left_reports(tmp_path) == []
