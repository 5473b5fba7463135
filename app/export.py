"""File ▸ Save reconstruction as BVH: the whole clip solved off the GUI thread.

The work is the session's :class:`engine.studio.export.ExportJob` (solve, then write
atomically); this module runs it on a worker thread behind a progress dialog with
Cancel. The job checks the cancel flag after every frame, so cancelling (or quitting
the studio) stops it within one frame and nothing is written.
"""

from __future__ import annotations

import threading
from collections.abc import Callable
from typing import TYPE_CHECKING

from PyQt6.QtCore import QObject, QTimer, pyqtSignal
from PyQt6.QtWidgets import QProgressDialog, QWidget

from app.job_runner import cancellable_progress
from engine.joining import join_saying

if TYPE_CHECKING:
    from engine.methods.base import Method
    from engine.studio.export import ExportJob

POLL_MS = 100


class ReconstructionExport(QObject):
    """One export at a time; ``finished(ok, message)`` fires on the GUI thread when it ends.

    Parameters
    ----------
    parent : QWidget
        The window the progress dialog belongs to.
    factory : callable, optional
        ``factory(method name) -> Method``; default the engine's registry (tests pass a
        slow stand-in).
    """

    finished = pyqtSignal(bool, str)

    def __init__(self, parent: QWidget, factory: Callable[[str], Method] | None = None) -> None:
        super().__init__(parent)
        self._parent = parent
        self.factory = factory
        self.thread: threading.Thread | None = None
        self.dialog: QProgressDialog | None = None
        self.done = 0
        self.total = 0
        self._cancel = threading.Event()
        self._result: tuple[bool, str] | None = None
        self._poll = QTimer(self, interval=POLL_MS)
        self._poll.timeout.connect(self._check)

    @property
    def running(self) -> bool:
        return self.thread is not None

    def start(self, job: ExportJob) -> None:
        """Run ``job`` (:meth:`engine.studio.export.ExportJob.of_session`) off the GUI thread."""
        if self.running:
            raise RuntimeError("an export is already running")
        self.done, self.total, self._result = 0, len(job.motion), None
        self._cancel.clear()
        # not modal: the studio stays usable
        self.dialog = cancellable_progress(
            self._parent,
            "Save reconstruction",
            f"Reconstructing {self.total} frames with {job.method}...",
            self.total,
            self.cancel,
        )
        self.dialog.show()
        self.thread = threading.Thread(target=self._run, args=(job,), name="bvh-export", daemon=True)
        self.thread.start()
        self._poll.start()

    def cancel(self) -> None:
        """Ask the export to stop after the frame it is solving (nothing is written)."""
        self._cancel.set()
        if self.dialog is not None:
            self.dialog.setLabelText("Cancelling...")

    def _progress(self, frame: int) -> None:
        self.done = frame + 1

    def _run(self, job: ExportJob) -> None:
        try:
            rec = job.run(self.factory, self._progress, self._cancel.is_set)
            self._result = (False, "") if rec is None else (True, f"Saved {len(rec)} frames to {job.path}")
        except Exception as exc:  # the GUI shows it; the studio keeps running
            self._result = (False, f"{job.path}: {type(exc).__name__}: {exc}")

    def _check(self) -> None:
        if self.dialog is not None and not self._cancel.is_set():
            self.dialog.setValue(min(self.done, self.total))
        if self.thread is None or self.thread.is_alive():
            return
        self._poll.stop()
        self.thread = None
        self._close_dialog()
        ok, message = self._result or (False, "the export stopped unexpectedly")
        self.finished.emit(ok, message)

    def _close_dialog(self) -> None:
        if self.dialog is not None:
            self.dialog.canceled.disconnect(self.cancel)
            self.dialog.close()
            self.dialog.deleteLater()
            self.dialog = None

    def shutdown(self) -> None:
        """Cancel a running export and wait for the frame in hand (bounded, :func:`engine.joining.join_saying`)."""
        self._poll.stop()
        if self.thread is not None:
            self._cancel.set()
            join_saying(self.thread, lambda: "Save reconstruction, cancelled")
            self.thread = None
        self._close_dialog()
