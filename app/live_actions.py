"""Live trackers in the studio: File > Connect live source, File > Open tracker
recording, and the Live dock (status light, packet rate, latency, Record / Stop,
Calibrate with a countdown). Kept apart from the window, which only creates it with the
objects it needs."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path
from typing import TYPE_CHECKING

from PyQt6.QtCore import QSettings, Qt, QTimer
from PyQt6.QtWidgets import QDialog, QDockWidget, QFileDialog, QMainWindow

from app.save_folder import ask_save_path, save_folder
from engine.errors import UserError
from engine.studio import events as ev
from widgets.live_panel import (
    DEFAULT_CONVENTION,
    DEFAULT_HOST,
    DEFAULT_MAPPING,
    DEFAULT_PORT,
    ConnectDialog,
    LivePanel,
)

if TYPE_CHECKING:
    from engine.studio.session import Session
    from engine.tracker_io.live_source import LiveSource
    from widgets.plots import LossPlots
    from widgets.timeline import Timeline


class LiveActions:
    """The window's live-source operations.

    Parameters
    ----------
    window : QMainWindow
        Only as a Qt main window: the parent of its dialogs and dock, its title and
        status bar.
    session : Session
        Builds and owns the sources (:meth:`Session.connect_live`, :meth:`Session.open_recording`).
    timeline : Timeline
        Its range follows the stream.
    plots : LossPlots
        Cleared for a new source.
    settings : QSettings
        Remembers the last port.
    show_error : callable
        ``show_error(title, text)``: the window's error dialog.
    """

    def __init__(
        self,
        window: QMainWindow,
        session: Session,
        timeline: Timeline,
        plots: LossPlots,
        settings: QSettings,
        show_error: Callable[[str, str], None],
    ) -> None:
        self.w = window
        self.session, self.timeline, self.plots, self.settings = session, timeline, plots, settings
        self.show_error = show_error
        self.panel = LivePanel()
        self.dock = QDockWidget("Live trackers", window)
        self.dock.setObjectName("Live trackers")
        self.dock.setWidget(self.panel)
        window.addDockWidget(Qt.DockWidgetArea.RightDockWidgetArea, self.dock)
        latent = window.findChild(QDockWidget, "Latent")
        if latent is not None:  # a tab beside the latent view: room for the calibration text
            window.tabifyDockWidget(latent, self.dock)
            latent.raise_()
        self.panel.recordRequested.connect(self.record)
        self.panel.calibrateRequested.connect(self.calibrate)
        self.panel.disconnectRequested.connect(self.disconnect)
        self.timer = QTimer(window, interval=250)  # the status light: four times a second
        self.timer.timeout.connect(self.refresh)
        self.timer.start()
        self._frames = -1
        session.events.source.connect(self._show_source)

    def close(self) -> None:
        self.timer.stop()
        self.session.events.source.disconnect(self._show_source)

    @property
    def live(self) -> LiveSource | None:
        """The session's live source, if it has one."""
        return self.session.live_source

    # -- File menu ----------------------------------------------------------------------
    def connect_dialog(self) -> None:
        if not self.w.files.confirm_discard("connecting a live source"):
            return
        get = self.settings.value
        dlg = ConnectDialog(
            self.w,
            port=int(get("live_port", DEFAULT_PORT)),
            mapping=str(get("live_mapping", DEFAULT_MAPPING)),
            host=str(get("live_host", DEFAULT_HOST)),
            convention=str(get("live_convention", DEFAULT_CONVENTION)),
        )
        if dlg.exec() != QDialog.DialogCode.Accepted:
            return
        v = dlg.values()
        self.connect(v["host"], v["port"], v["mapping"], v["convention"])

    def connect(self, host: str, port: int, mapping: str = "", convention: str = DEFAULT_CONVENTION) -> bool:
        """Listen on ``host:port`` and play the stream live; errors show a dialog."""
        try:
            self.session.connect_live(host, port, mapping, convention)
        except UserError as exc:
            self.show_error("Cannot connect live source", str(exc))
            return False
        remembered = {
            "live_port": port,
            "live_host": host,
            "live_mapping": mapping or DEFAULT_MAPPING,
            "live_convention": convention,
        }
        for key, value in remembered.items():
            self.settings.setValue(key, value)  # offered again by the next Connect
        self.session.play()
        return True

    def open_recording_dialog(self) -> None:
        if not self.w.files.confirm_discard("opening a tracker recording"):
            return
        path, _ = QFileDialog.getOpenFileName(self.w, "Open tracker recording", "", "Tracker recording (*.jsonl)")
        if path:
            self.open_recording(path)

    def open_recording(self, path: str | Path) -> bool:
        try:
            self.session.open_recording(path)
        except UserError as exc:
            self.show_error("Cannot open tracker recording", str(exc))
            return False
        return True

    # -- the Live dock --------------------------------------------------------------------
    def _show_source(self, event: ev.SourceChanged) -> None:
        self.timeline.set_range(max(event.source.num_frames, 1), event.source.fps)
        self.plots.clear()
        self.w.setWindowTitle(f"DragPoser Studio - {event.name}")
        self._frames = -1
        self.panel.set_recording(False)
        if event.live:
            self.dock.raise_()
        self.refresh()

    def refresh(self) -> None:
        src = self.live
        if src is None or not src.receiver.running:
            self.panel.show_status(None)
            return
        snap = self.session.latest
        latency = snap.timing.get("latency_ms") if snap is not None else None
        self.panel.show_status(src.status(), latency)
        n = src.num_frames
        if n != self._frames:  # the timeline grows with the stream
            self._frames = n
            self.timeline.set_range(max(n, 1), src.fps)

    def record(self, on: bool) -> None:
        src = self.live
        if src is None:
            self.panel.set_recording(False)
            return
        if not on:
            self._finish_recording(src)
            return
        suggested = save_folder(self.settings) / "trackers.jsonl"
        path, _ = ask_save_path(self.w, "Record trackers to", suggested, "Tracker recording (*.jsonl)", self.settings)
        if not path:
            self.panel.set_recording(False)
            return
        try:
            src.start_recording(path)
        except (OSError, UserError) as exc:
            self.panel.set_recording(False)
            self.show_error("Cannot record", str(exc))

    def calibrate(self, countdown_s: float, window_s: float) -> None:
        src = self.live
        if src is not None:
            src.start_calibration(countdown_s, window_s)

    def _finish_recording(self, src: LiveSource) -> None:
        """Stop ``src``'s recording and say what became of it."""
        recording = src.recording
        path = src.stop_recording()
        if path is not None:
            self.w.statusBar().showMessage(f"Wrote {path}", 8000)
        elif recording:
            self.w.statusBar().showMessage("No tracker sample arrived while recording: no file was written", 8000)

    def disconnect(self) -> None:
        """Stop listening (the received frames stay on the timeline)."""
        src = self.live
        if src is not None:
            self._finish_recording(src)
            src.close()
            if src.num_frames == 0:  # the view said it waits for frames: none will come
                self.w.viewport.clear_pose("disconnected before any tracker frame arrived")
        self.panel.set_recording(False)
        self.refresh()
