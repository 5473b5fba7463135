"""Autosave and recovery of the studio and its pose windows (docs/reliability.md).

While ``dragposer-studio gui`` runs, each window with unsaved edits keeps its document in
the state folder (:func:`app.crash_report.state_folder`, where the crash logs are; files:
:mod:`engine.autosave`), written :data:`AUTOSAVE_MS` after the first change that follows a
write, so no edit older than that is lost:

* the studio: its scene (:meth:`engine.studio.session.Session.to_scene`: the clip's path,
  method, preset, sensors, constraints, settings, frame) and, after a range re-solve, the
  edited clip itself;
* each pose window: its scene with keys and the pose being made
  (:func:`engine.authoring.recovery.document`).

A window whose edits are saved (or undone back to the saved state) has no autosave;
closing a window removes its own, and a clean quit removes the whole session. The next
start finds what a crashed or killed studio left (:func:`engine.autosave.left_sessions`)
and offers *Recover last session* (:func:`offer`); recovering reopens the clip, puts the
edited clip back, applies the scene as one undo step and reopens the pose windows.
"""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path
from typing import TYPE_CHECKING, Any

from PyQt6.QtCore import QObject, QTimer, pyqtSignal
from PyQt6.QtWidgets import QMessageBox, QWidget

from engine.autosave import AutosaveSession, LeftSession
from engine.errors import OutputError, UserError

if TYPE_CHECKING:
    from app.pose_window import PoseWindow
    from app.shell import StudioShell
    from engine.motion.clip import Motion

#: A change is on disk at most this long after it was made, milliseconds.
AUTOSAVE_MS = 3000


class DocumentAutosave(QObject):
    """Writes one window's document through ``files`` (an :class:`AutosaveSession`) as
    ``name``, :data:`AUTOSAVE_MS` after a change (:meth:`changed`).

    ``document()`` returns ``(scene dict, edited clip or None)``, or None when the window
    has nothing unsaved (its file is then removed). ``saved(path)`` fires after each write
    (``path`` "" when the file was removed), ``failed(message)`` when a write fails (the
    next change tries again).
    """

    saved = pyqtSignal(str)
    failed = pyqtSignal(str)

    def __init__(
        self,
        files: AutosaveSession,
        name: str,
        document: Callable[[], tuple[dict[str, Any], Motion | None] | None],
        parent: QObject | None = None,
        interval_ms: int = AUTOSAVE_MS,
    ) -> None:
        super().__init__(parent)
        self.files, self.name, self.document = files, name, document
        self.timer = QTimer(self, singleShot=True, interval=interval_ms)
        self.timer.timeout.connect(self.write_now)
        self.closed = False
        self._watched: list[Any] = []

    def watch(self, *signals: Any) -> None:
        """Count every emission of ``signals`` (Qt or psygnal) as a change, until :meth:`discard`."""
        for signal in signals:
            signal.connect(self.changed)
            self._watched.append(signal)

    def changed(self, *_: Any) -> None:
        """Something in the document changed: write it when the interval has passed (a
        running interval is not restarted, so steady editing still writes every interval)."""
        if not self.timer.isActive():
            self.timer.start()

    def write_now(self) -> None:
        self.timer.stop()
        if self.closed:
            return
        try:
            doc = self.document()
            if doc is None:
                self.files.remove(self.name)
                path = ""
            else:
                path = str(self.files.write(self.name, doc[0], doc[1]))
        except (UserError, OutputError, OSError, ValueError) as exc:
            self.failed.emit(f"Autosave failed: {exc}")
            return
        self.saved.emit(path)

    def discard(self) -> None:
        """The window closed cleanly: stop watching and remove its file."""
        self.timer.stop()
        for signal in self._watched:
            signal.disconnect(self.changed)
        self._watched.clear()
        self.closed = True
        self.files.remove(self.name)


class StudioAutosave(QObject):
    """The autosave of a studio ``window`` and of the pose windows opened from it."""

    def __init__(self, window: StudioShell, files: AutosaveSession, interval_ms: int = AUTOSAVE_MS) -> None:
        super().__init__(window)  # type: ignore[arg-type]
        self.window, self.files, self.interval_ms = window, files, interval_ms
        self.studio = DocumentAutosave(files, "studio", self._studio_document, self, interval_ms)
        self.studio.failed.connect(lambda text: window.statusBar().showMessage(text, 8000))
        # every edit, undo and redo; a save (clean) removes the file
        self.studio.watch(window.undo.changed, window.session.events.frame)
        self.poses: list[DocumentAutosave] = []
        self._count = 0

    def studio_closed(self) -> None:
        """The studio window closed cleanly (the pose windows may stay open)."""
        self.studio.discard()

    def _studio_document(self) -> tuple[dict[str, Any], Motion | None] | None:
        from app.clip_saving import clip_edited

        w = self.window
        if w.undo.is_clean():
            return None
        return w.session.to_scene(), w.session.motion if clip_edited(w) else None

    def watch_pose(self, pose: PoseWindow) -> DocumentAutosave:
        """Keep ``pose``'s document too, until it closes."""
        self._count += 1
        auto = watch_pose(self.files, pose, f"pose{self._count}", self, self.interval_ms)
        self.poses = [p for p in self.poses if not p.closed] + [auto]
        return auto

    def write_now(self) -> None:
        """Write every document now (after a recovery: the recovered work is on disk
        before the files it came from are removed)."""
        self.studio.write_now()
        for auto in self.poses:
            auto.write_now()


def watch_pose(
    files: AutosaveSession, pose: PoseWindow, name: str, parent: QObject | None = None, interval_ms: int = AUTOSAVE_MS
) -> DocumentAutosave:
    """Autosave pose window ``pose`` through ``files`` as document ``name`` until it
    closes (its closeEvent discards :attr:`PoseWindow.autosave`)."""
    from engine.authoring.recovery import document

    session = pose.session
    auto = DocumentAutosave(
        files, name, lambda: (document(session), None) if session.dirty else None, parent, interval_ms
    )
    auto.failed.connect(lambda text: pose.statusBar().showMessage(text, 8000))
    auto.watch(session.events.history, session.events.frame)  # every edit, undo and save; the frame
    pose.autosave = auto
    return auto


def recover(window: StudioShell, left: LeftSession) -> list[str]:
    """Restore ``left`` into ``window`` (see the module doc) and remove its files; returns
    the problems met (each naming the file), empty when everything came back (the files
    are kept otherwise)."""
    problems: list[str] = []
    if "studio" in left.documents:
        try:
            _recover_studio(window, *left.read("studio"), where=str(left.documents["studio"]))
        except UserError as exc:
            problems.append(str(exc))
    for name in sorted(n for n in left.documents if n != "studio"):
        try:
            recover_pose(window, left.read(name)[0], str(left.documents[name]))
        except UserError as exc:
            problems.append(str(exc))
    if window.autosave is not None:
        window.autosave.write_now()
    if not problems:  # otherwise its files stay, offered again, until recovered or discarded
        left.discard()
    return problems


def _recover_studio(window: StudioShell, scene: dict[str, Any], edited: Motion | None, where: str) -> None:
    from engine.studio.scenes import scene_from_dict

    session = window.session
    scene_from_dict(scene, where)  # a broken scene changes nothing
    clip = scene.get("clip")
    if clip and (session.path is None or Path(clip) != session.path):
        if not window.files.open_path(str(clip), window.files.rig_map_of(clip), ask=False):
            raise UserError(f"{where}: cannot open its clip {clip}")
    session.pause()  # the recovered frame stays on screen (gui starts playing the clip)
    with window.undo.group("Recover last session"):  # one undo step puts back the session as started
        if edited is not None:
            original, path = session.motion, session.path

            def show(motion: Motion) -> None:
                with window.undo.same_clip():
                    session.set_motion(motion, path)

            show(edited)
            window.undo.record("recovered re-solved clip", show, original, edited)
        session.apply_scene(scene, where)


def recover_pose(window: StudioShell | None, scene: dict[str, Any], where: str) -> PoseWindow:
    """A pose window (over ``window``, with its autosave, when given) holding the
    recovered document ``scene``."""
    from app.authoring_actions import show_pose_window
    from app.pose_window import PoseWindow
    from engine.authoring.recovery import recover as recover_document
    from engine.authoring.session import AuthoringSession

    session = AuthoringSession.new()
    recover_document(session, scene, where)
    pose = PoseWindow(session, settings=window.settings if window is not None else None)
    if window is not None:
        show_pose_window(window, pose)
    else:
        pose.show()
    return pose


def offer(window: StudioShell, left: list[LeftSession]) -> QMessageBox | None:
    """Offer to recover the newest of ``left`` (non-modal; returned for tests); None
    when there is nothing. Recover restores it, Discard removes its files."""
    if not left:
        return None
    newest = left[0]
    import time

    when = time.strftime("%Y-%m-%d %H:%M:%S", time.localtime(newest.saved))
    kinds = ["the studio's scene" if "studio" in newest.documents else ""]
    poses = sum(n != "studio" for n in newest.documents)
    kinds.append(f"{poses} pose window{'s' * (poses != 1)}" if poses else "")
    box = QMessageBox(window if isinstance(window, QWidget) else None)
    box.setIcon(QMessageBox.Icon.Question)
    box.setWindowTitle("Recover last session")
    box.setText("The last session of DragPoser Studio did not quit cleanly. Recover its unsaved work?")
    box.setInformativeText(f"Autosaved {when}: {' and '.join(k for k in kinds if k)} ({newest.folder}).")
    recover_button = box.addButton("Recover last session", QMessageBox.ButtonRole.AcceptRole)
    discard_button = box.addButton("Discard", QMessageBox.ButtonRole.DestructiveRole)

    def answered(button: Any) -> None:
        if button is recover_button:
            problems = recover(window, newest)
            if problems:
                window.show_error("Recover last session", "\n".join(problems))
            else:
                window.statusBar().showMessage("Recovered the last session (Ctrl+Z undoes it)", 10000)
        elif button is discard_button:
            newest.discard()

    box.buttonClicked.connect(answered)
    box.setModal(False)
    box.show()
    return box
