"""File ▸ Export video...: ``render``'s options in a small dialog, then the video.

The studio window (the loaded clip, its tracker preset) and the pose window (the
bake) both export through :func:`export_video`: the dialog asks for the size, view,
layout, camera, ghost methods, whether the motion is the ground truth, a title and a
time code (the options of ``dragposer-studio render``, :class:`app.render_scene.RenderOptions`),
then the file name; :func:`write_video` renders it with a progress dialog and says
where the file was written (status bar and a message).
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

from PyQt6.QtCore import Qt
from PyQt6.QtWidgets import (
    QCheckBox,
    QComboBox,
    QDialog,
    QDialogButtonBox,
    QFileDialog,
    QFormLayout,
    QLineEdit,
    QListWidget,
    QListWidgetItem,
    QMessageBox,
    QProgressDialog,
)

from app.render_scene import CAMERAS, LAYOUTS, VIEWS, RenderOptions
from engine.errors import UserError

SIZES = ("640x360", "960x540", "1280x720", "1920x1080")


class ExportVideoDialog(QDialog):
    """The video's options; ghosts are offered only when there are trackers to solve from.

    Parameters
    ----------
    parent : QWidget
        Owner window.
    sensors : str or None
        The tracker preset drawn (and the ghosts' input); None: no trackers.
    methods : sequence of str
        Methods offered as ghosts.
    """

    def __init__(self, parent: Any, sensors: str | None, methods: tuple[str, ...] = ()) -> None:
        super().__init__(parent)
        self.setWindowTitle("Export video")
        self.sensors = sensors
        form = QFormLayout(self)
        self.size_box = QComboBox()
        self.size_box.addItems(SIZES)
        self.size_box.setCurrentText("960x540")
        self.view = QComboBox()
        self.view.addItems(VIEWS)
        self.view.setCurrentText("body")
        self.layout_box = QComboBox()
        self.layout_box.addItems(LAYOUTS)
        self.camera = QComboBox()
        self.camera.addItems(CAMERAS)
        self.camera.setCurrentText("follow")
        self.ghosts = QListWidget()
        for name in methods:
            item = QListWidgetItem(name)
            item.setFlags(item.flags() | Qt.ItemFlag.ItemIsUserCheckable)
            item.setCheckState(Qt.CheckState.Unchecked)
            self.ghosts.addItem(item)
        rows = max(1, min(len(methods), 5))
        self.ghosts.setFixedHeight(max(self.ghosts.sizeHintForRow(0), 16) * rows + 2 * self.ghosts.frameWidth() + 2)
        self.ghosts.setEnabled(bool(sensors))
        self.ghosts.setToolTip("methods reconstructing the motion from its trackers" if sensors
                               else "choose a tracker preset first: ghosts are solved from its trackers")  # fmt: skip
        self.truth = QCheckBox("the motion is the ground truth (green, named so)")
        self.timecode = QCheckBox("time and frame number")
        self.title = QLineEdit()
        self.title.setPlaceholderText("optional title above the legend")
        ghosts = f"Ghosts (from trackers {sensors})" if sensors else "Ghosts"
        for label, widget in (("Size", self.size_box), ("View", self.view), ("Layout", self.layout_box),
                              ("Camera", self.camera), (ghosts, self.ghosts), ("Ground truth", self.truth),
                              ("Time code", self.timecode), ("Title", self.title)):  # fmt: skip
            form.addRow(label, widget)
        box = QDialogButtonBox(QDialogButtonBox.StandardButton.Ok | QDialogButtonBox.StandardButton.Cancel)
        box.accepted.connect(self.accept)
        box.rejected.connect(self.reject)
        form.addRow(box)

    def options(self) -> RenderOptions:
        """The chosen options, as ``render`` takes them."""
        from app.render import parse_size

        ghosts = tuple(self.ghosts.item(i).text() for i in range(self.ghosts.count())
                       if self.ghosts.item(i).checkState() == Qt.CheckState.Checked)  # fmt: skip
        return RenderOptions(size=parse_size(self.size_box.currentText()), sensors=self.sensors, ghosts=ghosts,
                             view=self.view.currentText(), camera=self.camera.currentText(),
                             layout=self.layout_box.currentText(), truth=self.truth.isChecked(),
                             title=self.title.text().strip(), timecode=self.timecode.isChecked())  # fmt: skip


def write_video(parent: Any, motion: Any, path: str | Path, options: RenderOptions) -> str:
    """Render ``motion`` to ``path`` with a progress dialog; returns (and shows in the
    parent's status bar, when it has one) the line saying the file was written."""
    from app.render import render_video

    dialog = QProgressDialog("Rendering video...", "", 0, len(motion), parent)
    dialog.setCancelButton(None)
    dialog.setWindowModality(Qt.WindowModality.WindowModal)
    try:
        render_video(motion, Path(path), options, progress=lambda f: dialog.setValue(f + 1))
    finally:
        dialog.close()
    w, h = options.size
    done = f"Video written: {path} ({len(motion)} frames, {w}x{h} at {motion.fps:g} fps)"
    status = getattr(parent, "statusBar", None)
    if callable(status):
        status().showMessage(done, 15000)
    return done


def export_video(parent: Any, motion: Any, sensors: str | None, methods: tuple[str, ...] = (),
                 suggested: str = "") -> str | None:  # fmt: skip
    """Ask for the options and the file (``suggested`` is the name the save dialog
    offers), render, and say so; None when cancelled. Errors (bad options, a failed
    method or ffmpeg) are shown, not raised."""
    dialog = ExportVideoDialog(parent, sensors, methods)
    if dialog.exec() != QDialog.DialogCode.Accepted:
        return None
    path, _ = QFileDialog.getSaveFileName(parent, "Export video", suggested, "MP4 video (*.mp4)")
    if not path:
        return None
    try:
        done = write_video(parent, motion, path, dialog.options())
    except (UserError, OSError) as exc:
        QMessageBox.warning(parent, "Export video", str(exc))
        return None
    QMessageBox.information(parent, "Export video", done)
    return done
