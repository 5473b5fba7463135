"""File menu of the studio: open, recent files, save BVH / scene, screenshots.

Every failure shows a message box and leaves the session as it was. Files are written to
a temporary name and renamed, so nothing is ever half written.
"""

from __future__ import annotations

import json
import os
from pathlib import Path

from PyQt6.QtCore import QPoint
from PyQt6.QtGui import QImage, QPainter, QPixmap
from PyQt6.QtWidgets import QFileDialog, QMainWindow

from app.export import ReconstructionExport
from engine.errors import UserError

MAX_RECENT = 8


def _atomic_write_text(path: Path, text: str) -> None:
    tmp = path.with_name(path.name + ".tmp")
    tmp.write_text(text)
    os.replace(tmp, path)


class FileActions:
    """Holds the window's file operations (kept apart so the window stays about wiring).

    ``window`` is the studio's main window; this class uses its ``session``,
    ``settings``, ``viewport``, ``recent_menu``, ``show_error`` and status bar (it does
    not import the window's module, which imports this one).
    """

    def __init__(self, window: QMainWindow) -> None:
        self.w = window
        self.export = ReconstructionExport(window)
        self.export.finished.connect(self._export_finished)

    # -- opening ------------------------------------------------------------------------
    def open_dialog(self) -> None:
        start = str(Path(self.recent()[0]).parent) if self.recent() else ""
        path, _ = QFileDialog.getOpenFileName(self.w, "Open motion", start, "BVH motion (*.bvh)")
        if path:
            self.open_path(path)

    def open_path(self, path: str | Path) -> bool:
        """Load ``path``; on error show a dialog and keep the current clip."""
        try:
            self.w.session.open(path)
        except UserError as exc:
            self.w.show_error("Cannot open motion", str(exc))
            return False
        self.add_recent(str(path))
        self.w.setWindowTitle(f"DragPoser Studio - {Path(path).name}")
        self.w.statusBar().showMessage(f"Loaded {path} ({self.w.session.num_frames} frames)", 5000)
        return True

    def recent(self) -> list[str]:
        value = self.w.settings.value("recent_files", [])
        return [str(v) for v in (value if isinstance(value, list) else [value] if value else [])]

    def add_recent(self, path: str) -> None:
        items = [path] + [p for p in self.recent() if p != path]
        self.w.settings.setValue("recent_files", items[:MAX_RECENT])
        self.refresh_recent()

    def refresh_recent(self) -> None:
        menu = self.w.recent_menu
        menu.clear()
        for p in self.recent():
            menu.addAction(p, lambda p=p: self.open_path(p))
        menu.setEnabled(bool(self.recent()))

    # -- saving ---------------------------------------------------------------------
    def save_on_source_rig(self, path: str | None = None) -> None:
        """Like :meth:`save_reconstruction`, written onto the opened file's own rig."""
        self.save_reconstruction(path, on_source_rig=True)

    def save_reconstruction(self, path: str | None = None, on_source_rig: bool = False) -> None:
        """Reconstruct the whole clip off the GUI thread (progress, Cancel), then write it as
        BVH (canonical skeleton, or with ``on_source_rig`` the hierarchy of the file it was
        opened from)."""
        s = self.w.session
        if s.source is not None:
            return self.w.show_error("Not for tracker input", "Saving re-solves a clip. For trackers use "
                                     "`dragposer-studio reconstruct --trackers REC.jsonl --out OUT.bvh` on a "
                                     "recording (Live trackers > Record), or `live --out` (docs/trackers.md).")  # fmt: skip
        if s.motion is None:
            return self.w.show_error("Nothing to save", "Open a motion first.")
        if on_source_rig and getattr(s, "path", None) is None:
            return self.w.show_error("Nothing to save", "This clip was not opened from a BVH file.")
        if self.export.running:
            return self.w.statusBar().showMessage("An export is already running", 3000)
        if path is None:
            path, _ = QFileDialog.getSaveFileName(self.w, "Save reconstruction", "", "BVH motion (*.bvh)")
            if not path:
                return None
        source = s.path if on_source_rig else None
        self.export.start(s.motion, tuple(s.sensors.values()), tuple(s.constraints),
                          dict(s.settings), s.method, path, source)  # fmt: skip
        return None

    def _export_finished(self, ok: bool, message: str) -> None:
        if ok:
            self.w.statusBar().showMessage(message, 8000)
        elif not message:
            self.w.statusBar().showMessage("Export cancelled: nothing was written", 5000)
        else:
            self.w.show_error("Cannot save reconstruction", message)

    def shutdown(self) -> None:
        self.export.shutdown()

    # -- scenes ---------------------------------------------------------------------
    def save_scene(self, path: str | None = None) -> bool:
        if path is None:
            path, _ = QFileDialog.getSaveFileName(self.w, "Save scene", "", "Studio scene (*.json)")
            if not path:
                return False
        try:
            _atomic_write_text(Path(path), json.dumps(self.w.session.to_scene(), indent=2))
        except OSError as exc:
            self.w.show_error("Cannot save scene", f"{path}: {exc}")
            return False
        return True

    def load_scene(self, path: str | None = None) -> bool:
        if path is None:
            path, _ = QFileDialog.getOpenFileName(self.w, "Load scene", "", "Studio scene (*.json)")
            if not path:
                return False
        try:
            scene = json.loads(Path(path).read_text())
            clip = scene.get("clip")
            if clip and (self.w.session.path is None or Path(clip) != self.w.session.path):
                self.w.session.open(clip)
            self.w.session.apply_scene(scene, str(path))
        except (OSError, ValueError, UserError) as exc:
            self.w.show_error("Cannot load scene", f"{path}: {exc}")
            return False
        return True

    # -- screenshots ------------------------------------------------------------------
    def grab_window(self) -> QPixmap:
        """The whole window with the 3D view composited in (grab() may leave it black)."""
        pix = self.w.grab()
        vp = self.w.viewport
        img: QImage = vp.grab_image()
        ratio = pix.devicePixelRatio()
        pos = vp.mapTo(self.w, QPoint(0, 0))
        painter = QPainter(pix)
        painter.drawImage(pos, img.scaled(int(vp.width() * ratio), int(vp.height() * ratio)))
        painter.end()
        return pix

    def export_screenshot(self, path: str | None = None) -> bool:
        if path is None:
            path, _ = QFileDialog.getSaveFileName(self.w, "Export screenshot", "", "PNG image (*.png)")
            if not path:
                return False
        target = Path(path)
        tmp = target.with_name(target.stem + ".tmp" + (target.suffix or ".png"))
        if not self.grab_window().save(str(tmp)):
            self.w.show_error("Cannot export screenshot", f"{path}: could not write the image")
            return False
        os.replace(tmp, target)
        return True
