"""File ▸ Export video...: ``render``'s options in a small dialog, then the video.

The studio window (the loaded clip, its tracker preset) and the pose window (the
bake) both export through :func:`export_video`: the dialog asks for the frames (first
and last, as the timeline numbers them: from 0), size, view, layout, camera, ghost
methods, whether the motion is the ground truth, a title and a time code (the options
of ``dragposer-studio render``, :class:`app.render_scene.RenderOptions`), then the file
name (in the folder last saved into: :mod:`app.save_folder`); :func:`write_video`
renders it with a progress dialog whose Cancel stops the video at the next frame and
leaves no file, and says where the file was written (status bar and a message).

The frames start as the timeline's selection when there is one, else the whole clip;
they belong to this clip and are not remembered. The part is cut before the ghosts
solve it: a ghost starts solving at the first frame of the part (as ``render --start``
does), and the time code shows the clip's own time and frame numbers.

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
    QHBoxLayout,
    QLabel,
    QLineEdit,
    QListWidget,
    QListWidgetItem,
    QMessageBox,
    QProgressDialog,
    QPushButton,
    QSpinBox,
    QWidget,
)

from app.render_scene import CAMERAS, LAYOUTS, VIEWS, RenderOptions
from app.save_folder import ask_save_path, check_writable
from engine.errors import UserError
from engine.progress import Cancelled

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
    num_frames : int
        Frames of the motion: the range offered is 0 to ``num_frames - 1``.
    fps : float
        Its frame rate (the range's duration is shown in seconds).
    selection : (int, int) or None
        The timeline's selected frames (inclusive): the range offered first; None:
        the whole motion.
    """

    def __init__(
        self,
        parent: Any,
        sensors: str | None,
        methods: tuple[str, ...] = (),
        settings: QSettings | None = None,
        shown: str = "",
        num_frames: int = 1,
        fps: float = 60.0,
        selection: tuple[int, int] | None = None,
    ) -> None:
        from engine.methods.presets import preset_problem

        super().__init__(parent)
        self.setWindowTitle("Export video")
        self.sensors = sensors
        self.settings = settings
        self.shown = shown  # the method on screen: the first export's ghost
        form = QFormLayout(self)
        self.num_frames, self.fps = max(1, num_frames), fps
        frames_row = self._frames_row(selection)
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
            "methods reconstructing the motion from its trackers; each starts solving at the "
            "first frame of the range, as on a clip that begins there"
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
            ("Frames", frames_row),
            ("", self.frames_note),
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

    def _frames_row(self, selection: tuple[int, int] | None) -> QWidget:
        """First and last frame (spin boxes bounded by the clip and by each other) and
        a Whole clip button; the note under them says what the range holds."""
        last = self.num_frames - 1
        self.first = QSpinBox(minimum=0, maximum=last, keyboardTracking=False)
        self.last = QSpinBox(minimum=0, maximum=last, value=last, keyboardTracking=False)
        tip = (
            "Frames to draw, as the timeline numbers them (from 0), both included. "
            "Ghosts start solving at the first frame: a method that follows the motion over "
            "time starts afresh there. The time code shows the clip's own frame numbers."
        )
        for box in (self.first, self.last):
            box.setToolTip(tip)
            box.valueChanged.connect(self._frames_changed)
        self.whole = QPushButton("Whole clip")
        self.whole.setToolTip("every frame of the clip")
        self.whole.clicked.connect(lambda: self.set_frames(0, self.num_frames - 1))
        self.frames_note = QLabel()
        row = QWidget()
        lay = QHBoxLayout(row)
        lay.setContentsMargins(0, 0, 0, 0)
        for widget in (self.first, QLabel("to"), self.last, self.whole):
            lay.addWidget(widget)
        lay.addStretch(1)
        self.selection = None  # the timeline's, as offered
        if selection is not None:
            lo, hi = sorted(selection)
            self.selection = (max(0, lo), min(last, hi))
            self.set_frames(*self.selection)
        self._frames_changed()
        return row

    def set_frames(self, first: int, last: int) -> None:
        """Make the range ``first``-``last`` (inclusive)."""
        for box, value in ((self.first, first), (self.last, last)):
            box.blockSignals(True)  # bounded by each other: both move before they are bounded
            box.setRange(0, self.num_frames - 1)
            box.setValue(value)
            box.blockSignals(False)
        self._frames_changed()

    def _frames_changed(self) -> None:
        self.first.setMaximum(self.last.value())
        self.last.setMinimum(self.first.value())
        n = self.last.value() - self.first.value() + 1
        whole = n == self.num_frames
        self.whole.setEnabled(not whole)
        if whole:
            what = "the whole clip"
        elif (self.first.value(), self.last.value()) == self.selection:
            what = f"the timeline's selection, of frames 0-{self.num_frames - 1}"
        else:
            what = f"of frames 0-{self.num_frames - 1}"
        self.frames_note.setText(f"{n} frame{'s' * (n != 1)}, {n / self.fps:.2f} s: {what}")

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
            frames=self.frames(),
        )

    def frames(self) -> tuple[int, int] | None:
        """The range chosen, first and last frame included; None: the whole clip."""
        first, last = self.first.value(), self.last.value()
        return None if (first, last) == (0, self.num_frames - 1) else (first, last)


#: What the status bar says when the user cancelled a video.
CANCELLED = "Export cancelled: no video was written"


def write_video(parent: Any, motion: Any, path: str | Path, options: RenderOptions) -> str | None:
    """Render ``motion`` (the frames ``options.frames``) to ``path`` with a progress
    dialog; returns (and shows in the parent's status bar, when it has one) the line
    saying the file was written, or None when the user pressed Cancel: the video stops
    at the next frame (or while waiting for the ghosts), nothing is written and the
    status bar says so."""
    from PyQt6.QtWidgets import QApplication

    from app.render import check_frames, render_video

    first, last = check_frames(options.frames, len(motion))
    n = last - first + 1
    dialog = QProgressDialog(f"Rendering {n} frames...", "Cancel", 0, n, parent)
    dialog.setWindowTitle("Export video")
    dialog.setWindowModality(Qt.WindowModality.WindowModal)
    dialog.setMinimumDuration(300)  # a Cancel to press early, no flash for a short video
    dialog.setValue(0)

    def cancelled() -> bool:
        QApplication.processEvents()  # the click on Cancel (rendering runs on this thread)
        return dialog.wasCanceled()

    status = getattr(parent, "statusBar", None)
    try:
        render_video(motion, Path(path), options, progress=lambda f: dialog.setValue(f + 1), cancelled=cancelled)
    except Cancelled:
        if callable(status):
            status().showMessage(CANCELLED, 15000)
        return None
    finally:
        dialog.close()
        dialog.deleteLater()
    w, h = options.size
    part = f"frames {first}-{last}: " if options.frames is not None else ""
    done = f"Video written: {path} ({part}{n} frames, {w}x{h} at {motion.fps:g} fps)"
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
    selection: tuple[int, int] | None = None,
) -> str | None:
    """Ask for the options (remembered in ``settings``, the frames starting as the
    timeline's ``selection``) and the file (``suggested`` is the file the save dialog
    offers), render, and say so; None when cancelled (the options, the file or the
    render). A folder that cannot be written is said before rendering; errors (a failed
    method or ffmpeg) are shown, not raised."""
    dialog = ExportVideoDialog(parent, sensors, methods, settings, shown, len(motion), motion.fps, selection)
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
    if done is not None:
        QMessageBox.information(parent, "Export video", done)
    return done
