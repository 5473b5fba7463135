"""No silent exit: a crash report for every run of the studio, offered on the next start.

While the studio runs, ``crash-<pid>.log`` in the state folder (:func:`state_folder`)
holds a header (versions, platform, start time) and the last user input (key and mouse
presses, wheel turns, the widget that got them). :mod:`faulthandler` writes the Python
stack of every thread there when the process dies of a fatal signal (segmentation
fault, abort, bus error, illegal instruction; on Python 3.14 and later the native C
stack too); an exception that no slot caught is written there with its traceback and
shown in a message box instead of ending the process (PyQt ends it by default). A clean
exit deletes the file. A file left by a process that no longer runs is a crash (or a
kill): the next start renames it ``crash-<pid>.reported.log`` and offers to show it.
"""

from __future__ import annotations

import faulthandler
import os
import platform
import sys
import time
import traceback
from pathlib import Path
from typing import Any, TextIO

from PyQt6.QtCore import QEvent, QObject
from PyQt6.QtGui import QKeyEvent, QMouseEvent
from PyQt6.QtWidgets import QApplication, QMessageBox, QWidget

#: Environment variable naming the state folder (tests, several installs side by side).
STATE_ENV = "DRAGPOSER_STUDIO_STATE"
#: Input lines kept in the log; older ones are dropped when the log is rewritten.
MAX_INPUT_LINES = 400

_INPUT = {
    QEvent.Type.KeyPress: "key",
    QEvent.Type.MouseButtonPress: "press",
    QEvent.Type.MouseButtonRelease: "release",
    QEvent.Type.Wheel: "wheel",
}


def state_folder() -> Path:
    """``$DRAGPOSER_STUDIO_STATE``, else ``$XDG_STATE_HOME/dragposer-studio``, else
    ``~/.local/state/dragposer-studio``."""
    if os.environ.get(STATE_ENV):
        return Path(os.environ[STATE_ENV])
    base = os.environ.get("XDG_STATE_HOME") or str(Path.home() / ".local" / "state")
    return Path(base) / "dragposer-studio"


def _running(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        return True
    return True


def left_reports(folder: Path) -> list[Path]:
    """Crash logs of processes that no longer run, newest first, each renamed to
    ``crash-<pid>.reported.log`` so it is offered once."""
    out = []
    for path in folder.glob("crash-*.log"):
        stem = path.name[len("crash-") : -len(".log")]
        if not stem.isdigit() or int(stem) == os.getpid() or _running(int(stem)):
            continue
        done = path.with_name(f"crash-{stem}.reported.log")
        try:
            path.replace(done)
        except OSError:
            continue
        out.append(done)
    return sorted(out, key=lambda p: p.stat().st_mtime, reverse=True)


def _header() -> str:
    import vtkmodules
    from PyQt6.QtCore import PYQT_VERSION_STR, QT_VERSION_STR

    return (
        f"DragPoser Studio, pid {os.getpid()}, started {time.strftime('%Y-%m-%d %H:%M:%S')}\n"
        f"Python {platform.python_version()}, Qt {QT_VERSION_STR}, PyQt {PYQT_VERSION_STR}, "
        f"VTK {getattr(vtkmodules, '__version__', '?')}, {platform.platform()}\n"
        f"command: {' '.join(sys.argv)}\n"
    )


class CrashLog(QObject):
    """The running studio's crash log (see the module doc). :meth:`start` it once the
    QApplication exists; :meth:`close` it on a clean exit."""

    def __init__(self, folder: Path | None = None) -> None:
        super().__init__()
        self.folder = folder or state_folder()
        self.path = self.folder / f"crash-{os.getpid()}.log"
        self.file: TextIO | None = None
        self.errors = 0
        self._lines = 0
        self._header = ""
        self._hook: Any = None
        self._was_enabled = False

    def start(self) -> None:
        # a handler already on (pytest's, ``python -X faulthandler``) is put back by close()
        self._was_enabled = faulthandler.is_enabled()
        self.folder.mkdir(parents=True, exist_ok=True)
        self._header = _header()
        self._rewrite([])
        app = QApplication.instance()
        if app is not None:
            app.installEventFilter(self)
        self._hook, sys.excepthook = sys.excepthook, self.excepthook

    def _rewrite(self, lines: list[str]) -> None:
        if self.file is not None:
            faulthandler.disable()
            self.file.close()
        self.file = open(self.path, "w", encoding="utf-8", buffering=1)  # noqa: SIM115 (kept open for faulthandler)
        self.file.write(self._header + "\nlast input (oldest first):\n" + "".join(lines))
        self.file.flush()
        self._lines = len(lines)
        extra = {"c_stack": True} if sys.version_info >= (3, 14) else {}
        faulthandler.enable(self.file, all_threads=True, **extra)

    def note(self, line: str) -> None:
        """Add one line of input to the log (the oldest go past :data:`MAX_INPUT_LINES`)."""
        if self.file is None:
            return
        if self._lines >= MAX_INPUT_LINES:
            text = self.path.read_text(encoding="utf-8", errors="replace")
            kept = text.split("last input (oldest first):\n", 1)[-1].splitlines(keepends=True)
            self._rewrite(kept[-MAX_INPUT_LINES // 2 :])
        self.file.write(f"{time.strftime('%H:%M:%S')} {line}\n")
        self._lines += 1

    def eventFilter(self, obj: QObject | None, event: QEvent | None) -> bool:  # noqa: N802 (Qt's name)
        kind = _INPUT.get(event.type()) if event is not None else None
        if kind is not None and isinstance(obj, QWidget):
            what = type(obj).__name__ + (f"({obj.objectName()})" if obj.objectName() else "")
            if isinstance(event, QKeyEvent):
                detail = f"{event.key():#x} {event.text()!r} mods {event.modifiers().value:#x}"
            elif isinstance(event, QMouseEvent):
                detail = f"button {event.button().value} at {event.position().x():.0f},{event.position().y():.0f}"
            else:
                detail = ""
            self.note(f"{kind} {detail} on {what}")
        return False

    def excepthook(self, kind: type, value: BaseException, tb: Any) -> None:
        """Log an exception nothing caught and show it; the studio goes on."""
        text = "".join(traceback.format_exception(kind, value, tb))
        self.errors += 1
        if self.file is not None:
            self.file.write(f"\nuncaught exception:\n{text}")
            self.file.flush()
        sys.stderr.write(text)
        if QApplication.instance() is not None and self.errors <= 3:  # no cascade of boxes
            QMessageBox.critical(
                None, "Internal error", f"{kind.__name__}: {value}\n\nThe studio goes on; details are in {self.path}."
            )

    def close(self) -> None:
        """A clean exit: stop logging and delete the log."""
        app = QApplication.instance()
        if app is not None:
            app.removeEventFilter(self)
        if sys.excepthook == self.excepthook:
            sys.excepthook = self._hook
        if self.file is not None:
            faulthandler.disable()
            self.file.close()
            self.file = None
            self.path.unlink(missing_ok=True)
            if self._was_enabled:
                faulthandler.enable(sys.__stderr__, all_threads=True)


def offer(parent: QWidget | None, reports: list[Path]) -> QMessageBox | None:
    """Tell the user the last session ended unexpectedly and offer its report (the
    message box's details); non-modal, returned for tests. None without reports."""
    if not reports:
        return None
    newest = reports[0]
    text = newest.read_text(encoding="utf-8", errors="replace")
    crashed = "Fatal Python error" in text or "uncaught exception" in text
    box = QMessageBox(parent)
    box.setIcon(QMessageBox.Icon.Warning)
    box.setWindowTitle("The studio ended unexpectedly")
    how = "crashed" if crashed else "ended without closing (killed, or the machine stopped)"
    box.setText(f"The last session of DragPoser Studio {how}.")
    box.setInformativeText(
        f"Its report was saved to {newest}. Click Show Details to read it; "
        "attach it to a bug report with what you were doing."
    )
    box.setDetailedText(text)
    box.setStandardButtons(QMessageBox.StandardButton.Ok)
    box.setModal(False)
    box.show()
    return box
