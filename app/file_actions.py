"""File menu of the studio: open, recent files, save BVH or glTF / scene, screenshots.

Every failure shows a message box and leaves the session as it was. Files are written to
a temporary name and renamed, so nothing is ever half written.
"""

from __future__ import annotations

import dataclasses
import json
from collections.abc import Callable
from pathlib import Path
from typing import TYPE_CHECKING

from PyQt6.QtCore import QPoint, QSettings
from PyQt6.QtGui import QImage, QPainter, QPixmap
from PyQt6.QtWidgets import QFileDialog, QMainWindow, QMenu, QMessageBox, QWidget

from app import rig_maps
from app.clip_saving import clip_edited
from app.export import ReconstructionExport
from app.motion_files import ask_motion_path
from app.save_folder import ask_save_path, check_writable, save_folder
from engine.atomic import atomic_path, write_text
from engine.errors import OutputError, RigError, UserError
from engine.input_files import read_json
from engine.motion.formats import motion_format
from engine.studio.scenes import scene_from_dict

if TYPE_CHECKING:
    from engine.studio.session import Session
    from widgets.viewport import Viewport

MAX_RECENT = 8


#: File types of the Open dialog: an AMC motion's ASF skeleton is found beside it
#: (engine.motion.source_file).
OPEN_FILTER = "Motion files (*.bvh *.amc);;BVH motion (*.bvh);;ASF/AMC motion (*.amc)"


class FileActions:
    """Holds the window's file operations (kept apart so the window stays about wiring).

    Parameters
    ----------
    window : QMainWindow
        Only as a Qt main window: the parent of dialogs, its title, status bar and grab
        (this module does not import the window's, which imports this one).
    session : Session
        Opens clips and scenes, builds exports.
    settings : QSettings
        Recent files and remembered joint mapping files.
    viewport : Viewport
        Composited into screenshots.
    show_error : callable
        ``show_error(title, text)``: the window's error dialog.

    Attributes
    ----------
    recent_menu : QMenu or None
        File > Open recent, filled by :meth:`refresh_recent` once the menus give it.
    """

    def __init__(
        self,
        window: QMainWindow,
        session: Session,
        settings: QSettings,
        viewport: Viewport,
        show_error: Callable[[str, str], None],
    ) -> None:
        self.w = window
        self.session, self.settings, self.viewport, self.show_error = session, settings, viewport, show_error
        self.recent_menu: QMenu | None = None
        self.export = ReconstructionExport(window)
        self.export.finished.connect(self._export_finished)
        self.rig_maps = rig_maps.RigMaps(settings)
        # dialogs, as attributes so tests can answer them without a modal box
        self.ask_unmapped = rig_maps.ask_unmapped
        self.pick_rig_map = rig_maps.pick_rig_map
        self.tell = rig_maps.tell
        #: ``confirm_discard(doing) -> bool`` before another file replaces the edits (the
        #: window's unsaved-changes prompt; True goes ahead)
        self.confirm_discard: Callable[[str], bool] = lambda doing: True
        #: ``ask_constraints(parent, names, clip) -> "remove" | "keep" | "cancel"``: what
        #: becomes of the constraints placed for the clip ``clip`` when another one opens
        self.ask_constraints: Callable[[QWidget, tuple[str, ...], str], str] = ask_constraints

    # -- opening ------------------------------------------------------------------------
    def open_dialog(self) -> None:
        start = str(Path(self.recent()[0]).parent) if self.recent() else ""
        path, _ = QFileDialog.getOpenFileName(self.w, "Open motion", start, OPEN_FILTER)
        if path:
            self.open_path(path)

    def open_path(
        self, path: str | Path, rig_map: str | Path | None = None, ask: bool = True, constraints: str = "keep"
    ) -> bool:
        """Load ``path`` (with the joint mapping file ``rig_map``, else the one remembered
        for it); on error show a dialog and keep the current clip. A rig that cannot be
        mapped leads to :meth:`_unmapped`. With ``ask``, unsaved edits are offered for
        saving first (:attr:`confirm_discard`) and constraints placed for the clip open
        now are removed or kept as the user says (:attr:`ask_constraints`; without
        ``ask``, as ``constraints`` says). Removing them is one undo step."""
        if ask:
            if not self.confirm_discard("opening another clip"):
                return False
            constraints = self._constraints_choice()
            if constraints == "cancel":
                return False
        rig_map = rig_map or self.rig_maps.get(path)
        try:
            self.session.open(path, rig_map)
        except RigError as exc:
            return self._unmapped(path, exc, constraints)
        except UserError as exc:
            self.show_error("Cannot open motion", str(exc))
            return False
        if constraints == "remove" and len(self.session.constraints):
            count = len(self.session.constraints)
            with self.w.undo.group(f"Remove the previous clip's {count} constraint{'s' * (count > 1)}"):
                self.session.set_constraints([])
        if rig_map:
            self.rig_maps.remember(path, rig_map)
        self.add_recent(str(path))
        self.w.setWindowTitle(f"DragPoser Studio - {Path(path).name}")
        shown = f" with {Path(rig_map).name}" if rig_map else ""
        self.w.statusBar().showMessage(f"Loaded {path}{shown} ({self.session.num_frames} frames)", 5000)
        return True

    def _constraints_choice(self) -> str:
        """``"remove"``, ``"keep"`` or ``"cancel"`` for the constraints of the clip open
        now ("keep" when there are none: nothing to ask)."""
        names = self.session.constraints.names
        if not names:
            return "keep"
        motion = self.session.motion
        clip = Path(self.session.path).name if self.session.path else motion.name if motion else "the open clip"
        return self.ask_constraints(self.w, names, clip)

    def _unmapped(self, path: str | Path, exc: RigError, constraints: str = "keep") -> bool:
        """Offer a mapping file for a rig that is not recognised, or write a suggestion."""
        choice = self.ask_unmapped(self.w, str(path), str(exc))
        if choice == "pick":
            chosen = self.pick_rig_map(self.w, str(Path(path).parent))
            return self.open_path(path, chosen, ask=False, constraints=constraints) if chosen else False
        if choice == "suggest":
            from engine.cli.rig import write_suggestion

            out = rig_maps.suggestion_path(path)
            try:
                complete = write_suggestion(Path(path), out)
            except (UserError, OSError) as err:
                self.show_error("Cannot suggest a mapping", str(err))
                return False
            what = "the mapping guessed" if complete else "a template listing the file's joints"
            self.w.statusBar().showMessage(f"Mapping suggestion written to {out}", 10000)
            self.tell(
                self.w,
                "Mapping suggested",
                f"Wrote {what} to\n{out}\n\nCheck and complete it, then "
                "open the file again and choose 'Pick mapping file...' (or pass it as "
                "--rig-map to any dragposer-studio command).",
            )
        return False

    def rig_map_of(self, path: str | Path | None) -> Path | None:
        """The mapping file remembered for an opened BVH, if any."""
        return None if path is None else self.rig_maps.get(path)

    def recent(self) -> list[str]:
        value = self.settings.value("recent_files", [])
        return [str(v) for v in (value if isinstance(value, list) else [value] if value else [])]

    def add_recent(self, path: str) -> None:
        items = [path] + [p for p in self.recent() if p != path]
        self.settings.setValue("recent_files", items[:MAX_RECENT])
        self.refresh_recent()

    def refresh_recent(self) -> None:
        menu = self.recent_menu
        if menu is None:
            return
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
        BVH or glTF by the extension (canonical skeleton, or with ``on_source_rig`` the hierarchy of the file it was
        opened from)."""
        from engine.studio.export import ExportJob

        s = self.session
        if s.source is not None:  # not an error: a pointer to what does it (an information box)
            QMessageBox.information(
                self.w,
                "Not for tracker input",
                "Saving re-solves a clip. For trackers use "
                "`dragposer-studio reconstruct --trackers REC.jsonl --out OUT.bvh` on a "
                "recording (Live trackers > Record), or `live --out` (docs/trackers.md).",
            )
            return None
        if self.export.running:
            return self.w.statusBar().showMessage("An export is already running", 3000)
        try:  # checked before a file is asked for
            job = ExportJob.of_session(s, path or "", on_source_rig)
        except UserError as exc:
            text = str(exc)
            return self.show_error("Nothing to save", f"{text[:1].upper()}{text[1:]}.")
        if path is None:
            path = ask_motion_path(self.w, "Save reconstruction", self.suggested_name("bvh"), self.settings)
            if not path:
                return None
            job = dataclasses.replace(job, path=Path(path))
        try:  # an extension no writer knows, a folder that cannot be written: said before the solve
            motion_format(path, "file")
            check_writable(path)
        except UserError as exc:
            return self.show_error("Cannot save reconstruction", str(exc))
        self.export.start(job)
        return None

    def _export_finished(self, ok: bool, message: str) -> None:
        if ok:
            self.w.statusBar().showMessage(message, 8000)
        elif not message:
            self.w.statusBar().showMessage("Export cancelled: nothing was written", 5000)
        else:
            self.show_error("Cannot save reconstruction", message)

    def shutdown(self) -> None:
        self.export.shutdown()

    def suggested_name(self, ext: str, what: str | None = None) -> str:
        """A file name the save dialogs offer, named after the open clip and the method
        (``walk_dragposer.bvh``) or after ``what`` (``walk_scene.json``), in the folder
        last saved into, else beside the clip when the user may write there, else in the
        home folder (:func:`app.save_folder.save_folder`)."""
        clip = self.session.path
        stem = Path(clip).stem if clip else "studio"
        name = f"{stem}_{what or self.session.method}.{ext}"
        return str(save_folder(self.settings, clip) / name)

    # -- scenes ---------------------------------------------------------------------
    def save_scene(self, path: str | None = None) -> bool:
        if path is None:
            path, _ = ask_save_path(
                self.w, "Save scene", self.suggested_name("json", "scene"), "Studio scene (*.json)", self.settings
            )
            if not path:
                return False
        try:
            write_text(path, json.dumps(self.session.to_scene(), indent=2, allow_nan=False) + "\n")
        except (OSError, ValueError) as exc:
            self.show_error("Cannot save scene", f"{path}: {exc}")
            return False
        if not clip_edited(self.w):  # a re-solved clip is saved apart (app.clip_saving)
            self.w.undo.set_clean()
        return True

    def load_scene(self, path: str | None = None) -> bool:
        if not self.confirm_discard("loading another scene"):
            return False
        if path is None:
            path, _ = QFileDialog.getOpenFileName(self.w, "Load scene", "", "Studio scene (*.json)")
            if not path:
                return False
        try:
            scene = read_json(path, "scene")  # size, UTF-8, depth; errors name the file and line
            clip = scene.get("clip") if isinstance(scene, dict) else None
            if clip and (self.session.path is None or Path(clip) != self.session.path):
                self.session.open(clip, self.rig_map_of(clip))
            scene_from_dict(scene, str(path))  # a scene that fails changes nothing, leaves no undo step
            with self.w.undo.group(f"Load scene {Path(path).name}"):  # one undo step puts back all it replaced
                done = self.session.apply_scene(scene, str(path))
        except (OSError, ValueError, UserError) as exc:
            text = str(exc)
            self.show_error("Cannot load scene", text if str(path) in text else f"{path}: {text}")
            return False
        self.w.undo.set_clean()  # the scene as loaded is what is saved
        self.w.statusBar().showMessage(f"Loaded {Path(path).name}: {done}", 15000)
        return True

    # -- screenshots ------------------------------------------------------------------
    def grab_window(self) -> QPixmap:
        """The whole window with the 3D view composited in (grab() may leave it black)."""
        pix = self.w.grab()
        vp = self.viewport
        img: QImage = vp.grab_image()
        ratio = pix.devicePixelRatio()
        pos = vp.mapTo(self.w, QPoint(0, 0))
        painter = QPainter(pix)
        painter.drawImage(pos, img.scaled(int(vp.width() * ratio), int(vp.height() * ratio)))
        painter.end()
        return pix

    def export_screenshot(self, path: str | None = None) -> bool:
        if path is None:
            path, _ = ask_save_path(
                self.w, "Export screenshot", self.suggested_name("png", "studio"), "PNG image (*.png)", self.settings
            )
            if not path:
                return False
        pix = self.grab_window()
        try:
            with atomic_path(path, suffix=Path(path).suffix or ".png") as tmp:
                if not pix.save(str(tmp), "PNG"):
                    raise OutputError(f"{path}: could not write the image")
        except OutputError as exc:
            self.show_error("Cannot export screenshot", str(exc))
            return False
        return True


def ask_constraints(parent: QWidget, names: tuple[str, ...], clip: str) -> str:
    """Ask whether the constraints placed for ``clip`` go or stay when another clip opens:
    ``"remove"`` (the default), ``"keep"`` or ``"cancel"`` (stay on this clip)."""
    shown = ", ".join(names[:6]) + (f" and {len(names) - 6} more" if len(names) > 6 else "")
    box = QMessageBox(
        QMessageBox.Icon.Question,
        "Constraints of the open clip",
        f"The scene holds {len(names)} constraint{'s' * (len(names) > 1)} placed for {clip}: {shown}.",
        QMessageBox.StandardButton.Cancel,
        parent,
    )
    box.setInformativeText(
        "They stay where they are in the world, and the new clip's performer moves elsewhere. "
        "Remove them (Edit > Undo brings them back) or keep them?"
    )
    remove = box.addButton("Remove", QMessageBox.ButtonRole.AcceptRole)
    keep = box.addButton("Keep", QMessageBox.ButtonRole.ActionRole)
    box.setDefaultButton(remove)
    box.exec()
    return {remove: "remove", keep: "keep"}.get(box.clickedButton(), "cancel")
