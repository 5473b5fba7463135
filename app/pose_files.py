"""The pose window's files: a new pose, open and save the scene, export the bake as BVH
or MP4, screenshots.

File ▸ New pose starts an empty document in the same window (its keys, targets and
constraints dropped, the character standing in the pose model's mean pose, at the height
asked for), after asking about unsaved edits as closing does.

Opening a scene (File ▸ Open scene) is a new document: it is read and checked as
``bake`` reads it, the model takes its keys, animation, constraints and settings (and
its character's height), goes to its first key and starts a new undo history
(:meth:`engine.authoring.session.AuthoringSession.open_scene`); what
only the studio uses (sensors, clip) is left and the status bar says so. Unsaved edits
are offered for saving first, as on closing. Exports bake the keys first, off the GUI
thread with a Cancel (:mod:`app.pose_timeline`). Every save dialog starts in the folder
last saved into (by this window or the studio), else the opened scene's folder when it
is writable, else the user's home (:func:`app.save_folder.save_folder`), with a name
(``pose.json``, ``pose.bvh``, ``pose.mp4``, or the saved scene's name with the export's
suffix); a finished export says so in the status bar with its path.
"""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path
from typing import Any

from PyQt6.QtWidgets import QFileDialog, QMessageBox

from app.motion_files import ask_motion_path
from app.save_folder import ask_save_path, remember_save_folder, save_folder
from engine.authoring.document import authoring_from_dict, save_authoring
from engine.errors import UserError
from engine.motion.formats import motion_format, save_motion

#: How long the status bar shows that a file was written, milliseconds.
DONE_MS = 10000


class PoseFiles:
    """Files of the pose window ``w`` (its ``session``, ``scene``, ``playback``)."""

    def __init__(self, w: Any) -> None:
        self.w = w
        self.path: Path | None = None  # the scene as last saved
        self.folder = Path.home()  # of the scene last opened or written: where Open starts

    def suggested(self, suffix: str) -> str:
        """Where a save dialog for a ``suffix`` file starts (see the module doc)."""
        stem = self.path.stem if self.path is not None else "pose"
        return str(save_folder(self.w.settings, self.folder) / f"{stem}{suffix}")

    def _wrote(self, path: str | Path, what: str) -> None:
        self.folder = Path(path).resolve().parent
        remember_save_folder(self.w.settings, path)  # also a save without a dialog (Ctrl+S)
        self.w.statusBar().showMessage(f"{what} written to {path}", DONE_MS)

    def confirm_discard(self, doing: str) -> bool:
        """With unsaved edits, ask Save / Discard / Cancel before ``doing``; whether to go on."""
        if not self.w.dirty:
            return True
        buttons = QMessageBox.StandardButton
        answer = QMessageBox.question(
            self.w,
            "Unsaved changes",
            f"Save the keys and targets before {doing}?",
            buttons.Save | buttons.Discard | buttons.Cancel,
        )
        if answer == buttons.Discard:
            return True
        if answer != buttons.Save:
            return False
        path = self.ask_path("Save scene", "Scenes (*.json)", ".json")
        if not path:
            return False
        self.save(path)
        return True

    def new_dialog(self) -> None:
        """File ▸ New pose: with unsaved edits ask first, then the character's height
        (the current one offered) and a new, empty document in this window."""
        from PyQt6.QtWidgets import QDialog

        from app.new_pose_dialog import NewPoseDialog

        if not self.confirm_discard("starting a new pose"):
            return
        dialog = NewPoseDialog(self.w, has_clip=False, height=self.w.mode.character.height)
        if dialog.exec() == QDialog.DialogCode.Accepted:
            self.new(dialog.height_m.value())

    def new(self, height: float) -> None:
        """A new, empty document on a character ``height`` metres tall, standing in the
        pose model's mean pose (:meth:`engine.authoring.session.AuthoringSession.new_scene`);
        the next Save asks for a file name."""

        def new() -> None:
            self.w.session.new_scene(height)
            self.path = None
            self.w.statusBar().showMessage(f"New pose: a {height:.2f} m character, no keys", DONE_MS)

        self.w._edit(new)

    def open(self, path: str | Path) -> None:
        """Make the scene at ``path`` the window's (see the module doc)."""
        from engine.input_files import read_json

        doc = read_json(path, "scene")
        loaded = authoring_from_dict(doc, str(path))
        w = self.w
        w.session.open_scene(loaded)
        self.path = Path(path)
        left = [k for k in ("sensors", "clip", "preset", "method") if isinstance(doc, dict) and doc.get(k)]
        note = f"; left to the studio: {', '.join(left)}" if left else ""
        n = len(loaded.keys)
        w.statusBar().showMessage(
            f"Opened {Path(path).name}: {n} key{'s' * (n != 1)}, {len(loaded.constraints)} constraint(s){note}", DONE_MS
        )
        self.folder = Path(path).resolve().parent

    def open_dialog(self) -> None:
        if not self.confirm_discard("opening another scene"):
            return
        path, _ = QFileDialog.getOpenFileName(self.w, "Open scene", str(self.folder), "Scenes (*.json)")
        if path:
            try:
                self.open(path)
            except (UserError, OSError, ValueError) as exc:
                text = str(exc)
                QMessageBox.warning(self.w, "Open scene", text if str(path) in text else f"{path}: {text}")

    def save(self, path: str | Path) -> None:
        save_authoring(path, self.w.scene)
        self.path = Path(path)
        self.w.session.history.set_clean()
        self._wrote(path, "Scene")

    def export_bvh(self, path: str | Path) -> None:
        """Bake and write the motion, BVH or glTF by the extension of ``path``."""
        kind = motion_format(path, "file")  # before the bake
        save_motion(path, self.w.playback.baked_scene().motion)
        self._wrote(path, "BVH" if kind == ".bvh" else "glTF")

    def export_video(self, path: str | Path, size: tuple[int, int] = (960, 540)) -> None:
        """Render the bake to ``path`` (MP4, stick figure) and say so (a cancelled video
        says so itself: :func:`app.export_video_dialog.write_video`)."""
        from app.export_video_dialog import write_video
        from app.render_scene import RenderOptions

        if write_video(self.w, self.w.playback.baked_scene().motion, path, RenderOptions(size=size)) is not None:
            self._wrote(path, "Video")

    def ask_path(self, title: str, pattern: str, suffix: str) -> str:
        """A path from a save dialog ("" when cancelled)."""
        path, _ = ask_save_path(self.w, title, self.suggested(suffix), pattern, self.w.settings)
        return path

    def _dialog(self, title: str, pattern: str, suffix: str, action: Callable[[str], None]) -> None:
        path = self.ask_path(title, pattern, suffix)
        if path:
            try:
                action(path)
            except (UserError, OSError) as exc:
                QMessageBox.warning(self.w, title, str(exc))

    def save_dialog(self) -> None:
        self._dialog("Save scene", "Scenes (*.json)", ".json", self.save)

    def export_bvh_dialog(self) -> None:
        path = ask_motion_path(self.w, "Export motion", self.suggested(".bvh"), self.w.settings)
        if path:
            try:
                self.export_bvh(path)
            except (UserError, OSError) as exc:
                QMessageBox.warning(self.w, "Export motion", str(exc))

    def export_video_dialog(self) -> None:
        """The video options dialog (:mod:`app.export_video_dialog`) on the bake."""
        from app.export_video_dialog import export_video

        try:
            motion = self.w.playback.baked_scene().motion
        except UserError as exc:
            QMessageBox.warning(self.w, "Export video", str(exc))
            return
        export_video(self.w, motion, None, suggested=self.suggested(".mp4"), settings=self.w.settings)

    def screenshot(self, path: str | Path) -> bool:
        """Save the window, 3D view included, as a PNG (the studio's compositing)."""
        from types import SimpleNamespace

        from app.file_actions import FileActions

        shim = SimpleNamespace(w=self.w, viewport=self.w.viewport)  # what grab_window reads
        return FileActions.grab_window(shim).save(str(path))  # type: ignore[arg-type]
