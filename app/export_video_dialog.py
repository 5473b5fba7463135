"""File ▸ Export video...: ``render``'s options in a small dialog, then the video.

The studio window (the loaded clip, its tracker preset) and the pose window (the
bake) both export through :func:`export_video`: the dialog asks for the size, view,
layout, camera, ghost methods, whether the motion is the ground truth, a title and a
time code (the options of ``dragposer-studio render``, :class:`app.render_scene.RenderOptions`),
then the file name (in the folder last saved into: :mod:`app.save_folder`); :func:`write_video` renders it with a progress dialog and says
where the file was written (status bar and a message).

What cannot run is not offered: a ghost method that cannot reconstruct from the
motion's trackers (RPM needs head and hands, SparsePoser the six trackers:
:func:`engine.methods.presets.preset_problem`) is greyed out with the reason beside it,
and OK checks the options as ``render`` does (:func:`app.render.check_options`) before
the file dialog opens, so nothing fails once a file is chosen. The choices are
remembered (QSettings, ``export_video/...``) for the next export.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

from PyQt6.QtCore import QSettings, Qt
from PyQt6.QtWidgets import (
    QCheckBox,
    QComboBox,
    QDialog,
    QDialogButtonBox,
    QFormLayout,
    QLabel,
    QLineEdit,
    QListWidget,
    QListWidgetItem,
    QMessageBox,
    QProgressDialog,
)

from app.render_scene import CAMERAS, LAYOUTS, VIEWS, RenderOptions
from app.save_folder import ask_save_path, check_writable
from engine.errors import UserError

SIZES = ("640x360", "960x540", "1280x720", "1920x1080")
#: QSettings group of the remembered choices.
GROUP = "export_video"


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
    settings : QSettings or None
        Where the choices are remembered (None: not remembered).
    shown : str
        The method on screen, ticked as a ghost the first time (nothing remembered yet):
        a video of what the user sees.
    """

    def __init__(
        self,
        parent: Any,
        sensors: str | None,
        methods: tuple[str, ...] = (),
        settings: QSettings | None = None,
        shown: str = "",
    ) -> None:
        from engine.methods.presets import preset_problem

        super().__init__(parent)
        self.setWindowTitle("Export video")
        self.sensors = sensors
        self.settings = settings
        self.shown = shown  # the method on screen: the first export's ghost
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
        #: ghost method -> why it cannot run from these trackers
        self.impossible = {m: why for m in methods if sensors and (why := preset_problem(m, sensors))}
        for name in methods:
            item = QListWidgetItem(name if name not in self.impossible else f"{name} (cannot run: see below)")
            item.setData(Qt.ItemDataRole.UserRole, name)
            item.setFlags(item.flags() | Qt.ItemFlag.ItemIsUserCheckable)
            if name in self.impossible:
                item.setFlags(item.flags() & ~Qt.ItemFlag.ItemIsEnabled)
                item.setToolTip(self.impossible[name])
            item.setCheckState(Qt.CheckState.Unchecked)
            self.ghosts.addItem(item)
        rows = max(1, min(len(methods), 5))
        self.ghosts.setFixedHeight(max(self.ghosts.sizeHintForRow(0), 16) * rows + 2 * self.ghosts.frameWidth() + 2)
        self.ghosts.setEnabled(bool(sensors))
        self.ghosts.setToolTip(
            "methods reconstructing the motion from its trackers"
            if sensors
            else "choose a tracker preset first: ghosts are solved from its trackers"
        )
        self.truth = QCheckBox("the motion is the ground truth (green, named so)")
        self.timecode = QCheckBox("time and frame number")
        self.title = QLineEdit()
        self.title.setPlaceholderText("optional title above the legend")
        # why some choices are greyed out, and why OK refused, in words beside them
        self.note = QLabel("\n".join(self.impossible.values()))
        self.note.setWordWrap(True)
        self.note.setVisible(bool(self.impossible))
        ghosts = f"Ghosts (from trackers {sensors})" if sensors else "Ghosts"
        for label, widget in (
            ("Size", self.size_box),
            ("View", self.view),
            ("Layout", self.layout_box),
            ("Camera", self.camera),
            (ghosts, self.ghosts),
            ("", self.note),
            ("Ground truth", self.truth),
            ("Time code", self.timecode),
            ("Title", self.title),
        ):
            form.addRow(label, widget)
        box = QDialogButtonBox(QDialogButtonBox.StandardButton.Ok | QDialogButtonBox.StandardButton.Cancel)
        box.accepted.connect(self.accept)
        box.rejected.connect(self.reject)
        form.addRow(box)
        self._restore()

    def _restore(self) -> None:
        """The choices of the last export (those still possible)."""
        if self.settings is None:
            self._tick((self.shown,))
            return
        get = lambda key, default: self.settings.value(f"{GROUP}/{key}", default)  # noqa: E731
        for combo, key in (
            (self.size_box, "size"),
            (self.view, "view"),
            (self.layout_box, "layout"),
            (self.camera, "camera"),
        ):
            value = str(get(key, combo.currentText()))
            if combo.findText(value) >= 0:
                combo.setCurrentText(value)
        truthy = lambda v: str(v).lower() in ("true", "1")  # noqa: E731 (QSettings' ini files give strings)
        self.truth.setChecked(truthy(get("truth", False)))
        self.timecode.setChecked(truthy(get("timecode", False)))
        self.title.setText(str(get("title", "")))
        # the first export draws the method on screen (a video of what the user sees),
        # later ones what was chosen last
        self._tick(tuple(str(get("ghosts", self.shown)).split(",")))

    def _tick(self, ghosts: tuple[str, ...]) -> None:
        """Tick the ghosts named in ``ghosts`` that can run."""
        for i in range(self.ghosts.count()):
            item = self.ghosts.item(i)
            if item.flags() & Qt.ItemFlag.ItemIsEnabled and item.data(Qt.ItemDataRole.UserRole) in ghosts:
                item.setCheckState(Qt.CheckState.Checked)

    def _remember(self, options: RenderOptions) -> None:
        if self.settings is None:
            return
        for key, value in (
            ("size", self.size_box.currentText()),
            ("view", options.view),
            ("layout", options.layout),
            ("camera", options.camera),
            ("truth", options.truth),
            ("timecode", options.timecode),
            ("title", options.title),
            ("ghosts", ",".join(options.ghosts)),
        ):
            self.settings.setValue(f"{GROUP}/{key}", value)

    def accept(self) -> None:
        """Check the options as ``render`` would before the dialog closes (and so before
        the file dialog): a refusal is said under the ghosts and the dialog stays."""
        from app.render import check_options

        options = self.options()
        try:
            check_options(options)
        except UserError as exc:
            self.note.setText(str(exc))
            self.note.setVisible(True)
            return
        self._remember(options)
        super().accept()

    def options(self) -> RenderOptions:
        """The chosen options, as ``render`` takes them."""
        from app.render import parse_size

        ghosts = tuple(
            self.ghosts.item(i).data(Qt.ItemDataRole.UserRole)
            for i in range(self.ghosts.count())
            if self.ghosts.item(i).checkState() == Qt.CheckState.Checked
        )
        return RenderOptions(
            size=parse_size(self.size_box.currentText()),
            sensors=self.sensors,
            ghosts=ghosts,
            view=self.view.currentText(),
            camera=self.camera.currentText(),
            layout=self.layout_box.currentText(),
            truth=self.truth.isChecked(),
            title=self.title.text().strip(),
            timecode=self.timecode.isChecked(),
        )


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


def export_video(
    parent: Any,
    motion: Any,
    sensors: str | None,
    methods: tuple[str, ...] = (),
    suggested: str = "",
    settings: QSettings | None = None,
    shown: str = "",
) -> str | None:
    """Ask for the options (remembered in ``settings``) and the file (``suggested`` is
    the name the save dialog offers), render, and say so; None when cancelled. Errors
    (a failed method or ffmpeg) are shown, not raised."""
    dialog = ExportVideoDialog(parent, sensors, methods, settings, shown)
    if dialog.exec() != QDialog.DialogCode.Accepted:
        return None
    path, _ = ask_save_path(parent, "Export video", suggested, "MP4 video (*.mp4)", settings)
    if not path:
        return None
    try:
        check_writable(path)
        done = write_video(parent, motion, path, dialog.options())
    except (UserError, OSError) as exc:
        QMessageBox.warning(parent, "Export video", str(exc))
        return None
    QMessageBox.information(parent, "Export video", done)
    return done
