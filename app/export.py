"""File ▸ Save reconstruction as BVH: the whole clip solved off the GUI thread.

A progress dialog shows the frames solved and offers Cancel; the solver checks the
cancel flag after every frame, so cancelling (or quitting the studio) stops it within
one frame and nothing is written. The BVH is written to a temporary file and renamed
(:func:`engine.bvh.save_motion_bvh`), so a file is either complete or absent.
"""

from __future__ import annotations

import threading
from collections.abc import Callable, Mapping
from pathlib import Path
from typing import Any

from PyQt6.QtCore import QObject, Qt, QTimer, pyqtSignal
from PyQt6.QtWidgets import QProgressDialog, QWidget

POLL_MS = 100
#: How long quitting waits for a cancelled export to finish its current frame, seconds.
SHUTDOWN_WAIT_S = 3.0


class ExportCancelled(Exception):
    """The user cancelled the export (nothing was written)."""


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

    def __init__(self, parent: QWidget, factory: Callable[[str], Any] | None = None) -> None:
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

    def start(self, motion: Any, sensors: tuple, constraints: tuple, settings: Mapping[str, Any], method: str, path: str,
              source: Path | None = None, rig_map: Path | None = None) -> None:  # fmt: skip
        """Solve ``motion`` with ``method`` and the studio's edits, then write ``path`` (onto
        the hierarchy of the BVH ``source`` when given, mapped with the joint mapping file
        ``rig_map`` if any: docs/skeleton.md, --on-source-rig)."""
        if self.running:
            raise RuntimeError("an export is already running")
        self.done, self.total, self._result = 0, len(motion), None
        self._cancel.clear()
        self.dialog = QProgressDialog(f"Reconstructing {self.total} frames with {method}...", "Cancel",
                                      0, self.total, self._parent)  # fmt: skip
        self.dialog.setWindowTitle("Save reconstruction")
        self.dialog.setWindowModality(Qt.WindowModality.NonModal)  # the studio stays usable
        self.dialog.setMinimumDuration(0)
        self.dialog.setAutoClose(False)
        self.dialog.setAutoReset(False)
        self.dialog.canceled.connect(self.cancel)
        self.dialog.show()
        args = (motion, sensors, constraints, settings, method, path, source, rig_map)
        self.thread = threading.Thread(target=self._run, args=args, name="bvh-export", daemon=True)
        self.thread.start()
        self._poll.start()

    def cancel(self) -> None:
        """Ask the export to stop after the frame it is solving (nothing is written)."""
        self._cancel.set()
        if self.dialog is not None:
            self.dialog.setLabelText("Cancelling...")

    def _progress(self, frame: int) -> bool:
        self.done = frame + 1
        return self._cancel.is_set()

    def _run(self, motion: Any, sensors: tuple, constraints: tuple, settings: Mapping[str, Any], method: str, path: str,
             source: Path | None, rig_map: Path | None) -> None:  # fmt: skip
        try:
            from engine.bvh import save_motion_bvh
            from engine.studio.methods import reconstruct_clip

            result = reconstruct_clip(motion, sensors, constraints, settings, method,
                                      factory=self.factory, progress=self._progress)  # fmt: skip
            if self._cancel.is_set():
                raise ExportCancelled
            if source is None:
                save_motion_bvh(path, result)
            else:
                from engine.bvh import load_bvh
                from engine.retarget import manifest_fps, retarget
                from engine.source_rig import save_on_source_rig

                raw = load_bvh(source)
                save_on_source_rig(path, result, raw, retarget(raw, manifest_fps(source), rig_map=rig_map)[1])
            self._result = (True, f"Saved {len(result)} frames to {path}")
        except ExportCancelled:
            self._result = (False, "")
        except Exception as exc:  # the GUI shows it; the studio keeps running
            self._result = (False, f"{path}: {type(exc).__name__}: {exc}")

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
        """Cancel a running export and wait (briefly) for it: quitting never hangs on it."""
        self._poll.stop()
        if self.thread is not None:
            self._cancel.set()
            self.thread.join(timeout=SHUTDOWN_WAIT_S)
            self.thread = None
        self._close_dialog()
