"""Long authoring work off the GUI thread: a job on a worker, a progress dialog with Cancel.

:class:`JobRunner` runs one :mod:`engine.authoring.jobs` job at a time on a worker thread,
as the studio's export does (:mod:`app.export`): the job reads only the copy it was
made with, the GUI thread polls its progress into a :class:`QProgressDialog` and, when
it ends, hands the result to ``on_done`` on the GUI thread, which applies it to the
model as one command. Cancel (or closing the window) sets a flag the job checks between
frames, so it stops within a frame and nothing is applied.

:meth:`JobRunner.wait` runs the event loop until the job ends, for callers that need the
result before going on (the pose window's playing, scrubbing and exports need the bake):
the window keeps drawing and Cancel answers meanwhile, and a window-modal dialog keeps
edits out until the result is in.
"""

from __future__ import annotations

import threading
from collections.abc import Callable
from typing import Any

from PyQt6.QtCore import QEvent, QEventLoop, QObject, Qt, QTimer, pyqtSignal
from PyQt6.QtWidgets import QApplication, QProgressDialog, QWidget

from engine.errors import UserError
from engine.joining import join_saying
from engine.progress import Cancelled

#: How often the GUI thread reads the job's progress, milliseconds.
POLL_MS = 50
#: A job shorter than this shows no dialog, milliseconds (no flash for a quick bake).
SHOW_AFTER_MS = 300


class JobRunner(QObject):
    """One job at a time for the window ``parent``; ``finished(ok, message)`` fires on
    the GUI thread when a job ends (``ok`` False and message ``"cancelled"`` when it was
    cancelled, or the error's text)."""

    finished = pyqtSignal(bool, str)

    def __init__(self, parent: QWidget) -> None:
        super().__init__(parent)
        self._parent = parent
        self.thread: threading.Thread | None = None
        self.dialog: QProgressDialog | None = None
        self.done, self.total = 0, 0
        self.result: Any = None
        self.message = ""  # why the last job gave no result ("cancelled", an error)
        self._outcome: tuple[bool, str, Any] | None = None
        self._on_done: Callable[[Any], None] | None = None
        self._title = ""  # the running job's, for a close that waits for it
        self._cancel = threading.Event()
        self._window: QWidget | None = None
        self._active: QWidget | None = None  # closing it cancels the job (cancel_on_close)
        self._poll = QTimer(self, interval=POLL_MS)
        self._poll.timeout.connect(self._check)

    @property
    def running(self) -> bool:
        return self.thread is not None

    def start(self, job: Any, on_done: Callable[[Any], None] | None = None, modal: bool = False) -> None:
        """Run ``job`` (``run(progress, cancelled)``, ``title``, ``label``) on a worker;
        ``on_done(result)`` on the GUI thread when it succeeds. ``modal``: the dialog
        keeps input out of the window until the job ends."""
        if self.running:
            raise UserError(f"{job.title}: another job is running; wait for it or cancel it")
        self.done, self.total, self.result, self._outcome = 0, 0, None, None
        self._on_done = on_done
        self._title = job.title
        self._active = QApplication.activeWindow()  # gets the keyboard back from the dialog
        self._cancel.clear()
        dialog = cancellable_progress(self._parent, job.title, job.label, 0, self.cancel, modal, SHOW_AFTER_MS)
        dialog.setValue(0)  # starts the dialog's own timer: it shows after SHOW_AFTER_MS
        self.dialog = dialog
        self.thread = threading.Thread(target=self._run, args=(job,), name="authoring-job", daemon=True)
        self.thread.start()
        self._poll.start()

    def cancel(self) -> None:
        """Ask the job to stop after the frame it is solving (nothing is applied)."""
        self._cancel.set()
        if self.dialog is not None:
            self.dialog.setLabelText("Cancelling...")

    def wait(self) -> Any:
        """Run the event loop until the job ends; its result (None when cancelled or failed)."""
        if self.running:
            loop = QEventLoop()
            self.finished.connect(loop.quit)
            try:
                if self.running:  # it may have ended while connecting
                    loop.exec()
            finally:
                self.finished.disconnect(loop.quit)
        return self.result

    def _progress(self, done: int, total: int) -> None:
        self.done, self.total = done, total  # plain ints: the GUI thread only reads them

    def _run(self, job: Any) -> None:
        try:
            self._outcome = (True, "", job.run(self._progress, self._cancel.is_set))
        except Cancelled:
            self._outcome = (False, "cancelled", None)
        except UserError as exc:
            self._outcome = (False, str(exc), None)
        except Exception as exc:  # the window shows it and keeps running
            self._outcome = (False, f"{type(exc).__name__}: {exc}", None)

    def _check(self) -> None:
        if self.dialog is not None and not self._cancel.is_set() and self.total > 0:
            self.dialog.setMaximum(self.total)
            self.dialog.setValue(min(self.done, self.total))
        if self.thread is None or self.thread.is_alive():
            return
        self._poll.stop()
        self.thread = None
        self._close_dialog()
        ok, message, result = self._outcome or (False, "the job stopped unexpectedly", None)
        if ok and self._cancel.is_set():
            ok, message, result = False, "cancelled", None  # cancelled after its last frame
        if ok and self._on_done is not None:
            try:
                self._on_done(result)
            except UserError as exc:
                ok, message, result = False, str(exc), None
        self.result, self.message = result, message
        self.finished.emit(ok, message)

    def _close_dialog(self) -> None:
        if self.dialog is not None:
            self.dialog.canceled.disconnect(self.cancel)
            self.dialog.close()
            self.dialog.deleteLater()
            self.dialog = None
            # without a window manager (Xvfb) nothing hands the keyboard back to the
            # window the dialog covered, and its shortcuts (Space: play) stay dead
            if self._active is not None and self._active.isVisible():
                self._active.activateWindow()

    def shutdown(self) -> None:
        """Cancel a running job and wait for the frame or round in hand (bounded, said on
        stderr when it takes long, :func:`engine.joining.join_saying`): a worker left in
        torch when the process exits aborts it."""
        if self.thread is not None:
            self._cancel.set()
            title = self._title
            join_saying(self.thread, lambda: f"{title}, cancelled")
            self._check()  # ends a wait() and reports the cancel
        self._poll.stop()
        self._close_dialog()

    def cancel_on_close(self, window: QWidget) -> None:
        """Cancel the running job when ``window`` closes (a close it refuses leaves it running)."""
        window.installEventFilter(self)
        self._window = window

    def eventFilter(self, obj: QObject | None, event: QEvent | None) -> bool:  # noqa: N802 (Qt's name)
        if event is not None and event.type() == QEvent.Type.Close and obj is self._window:
            # the window may still refuse the close (unsaved edits): look once it is handled
            QTimer.singleShot(0, self._close_if_hidden)
        return False

    def _close_if_hidden(self) -> None:
        if self._window is not None and not self._window.isVisible():
            self.shutdown()


def cancellable_progress(
    parent: QWidget | None,
    title: str,
    label: str,
    maximum: int,
    cancel: Callable[[], None],
    modal: bool = False,
    show_after_ms: int = 0,
) -> QProgressDialog:
    """A progress dialog for work on another thread: Cancel calls ``cancel`` (the work stops
    between its steps), and the dialog neither closes nor resets itself when the bar is
    full, since the result is applied after it (``maximum`` 0: a busy bar)."""
    dialog = QProgressDialog(label, "Cancel", 0, maximum, parent)
    dialog.setWindowTitle(title)
    dialog.setWindowModality(Qt.WindowModality.WindowModal if modal else Qt.WindowModality.NonModal)
    dialog.setMinimumDuration(show_after_ms)
    dialog.setAutoClose(False)
    dialog.setAutoReset(False)
    dialog.canceled.connect(cancel)
    return dialog
