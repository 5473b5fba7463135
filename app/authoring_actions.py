"""The studio window's authoring entries: File ▸ New pose... and File ▸ Export video...

:func:`add_menu_entries` puts them in the File menu (one call from :mod:`app.menus`).
New pose asks for the character's height and whether to start from a neutral standing
pose (the pose model's average) or from the current frame of the loaded clip, and opens a
:class:`app.pose_window.PoseWindow` on a new authoring model
(:meth:`engine.authoring.session.AuthoringSession.new`, which loads the pose model). Export video renders the loaded clip with the
current tracker preset drawn on it, with the options of ``render`` chosen in a small
dialog (:mod:`app.export_video_dialog`).
"""

from __future__ import annotations

from collections.abc import Callable
from typing import TYPE_CHECKING

from PyQt6 import sip
from PyQt6.QtGui import QAction
from PyQt6.QtWidgets import QDialog, QMenu, QMessageBox

from app.new_pose_dialog import CLIP, NewPoseDialog
from engine.errors import UserError

if TYPE_CHECKING:
    from app.pose_window import PoseWindow
    from app.shell import StudioShell


def open_pose_window(window: StudioShell, height: float, from_clip: bool) -> PoseWindow:
    """Open a pose window over ``window`` (kept on ``window.pose_windows``) and return it."""
    from app.pose_window import PoseWindow
    from engine.authoring.session import AuthoringSession

    session = window.session
    clip = session.motion if from_clip else None
    pose = PoseWindow(AuthoringSession.new(height, clip, session.frame), settings=window.settings)
    show_pose_window(window, pose)
    return pose


def show_pose_window(window: StudioShell, pose: PoseWindow) -> None:
    """Show ``pose`` over ``window``: kept on ``window.pose_windows``, autosaved with the
    studio (:mod:`app.autosave`) when the studio autosaves."""
    window.pose_windows = [p for p in window.pose_windows if not sip.isdeleted(p) and p.isVisible()] + [pose]
    if window.autosave is not None:
        window.autosave.watch_pose(pose)
    pose.resize(1200, 800)
    pose.show()


def confirm_quit(window: StudioShell) -> bool:
    """Before the studio quits: ask every open pose window, then the studio, about its
    unsaved work, and close the pose windows when all agreed. A Cancel anywhere keeps
    every window open as it is (nothing has closed yet); True when the studio may close.

    The pose windows are top-level windows of their own: closing only the studio would
    leave them open, with their unsaved keys, and the process running."""
    from app.clip_saving import confirm_discard

    poses = [p for p in window.pose_windows if not sip.isdeleted(p) and p.isVisible()]
    for pose in poses:
        pose.raise_()  # the prompt is about this window's keys: show which one
        if not pose.files.confirm_discard("quitting"):
            return False
    if not confirm_discard(window, "quitting"):
        return False
    for pose in poses:
        pose.close_unasked()
    return True


def new_pose(window: StudioShell) -> None:
    dialog = NewPoseDialog(window, window.session.motion is not None)
    if dialog.exec() != QDialog.DialogCode.Accepted:
        return
    try:
        open_pose_window(window, dialog.height_m.value(), dialog.start.currentText() == CLIP)
    except UserError as exc:
        QMessageBox.warning(window, "New pose", str(exc))


def export_video(window: StudioShell) -> str | None:
    """File ▸ Export video...: the loaded clip with the current tracker preset, through
    the video options dialog (:mod:`app.export_video_dialog`); the frames start as the
    timeline's selection, when there is one."""
    from app.export_video_dialog import export_video as export

    motion = window.session.motion
    if motion is None:
        QMessageBox.warning(window, "Export video", "Open a clip first.")
        return None
    return export(
        window,
        motion,
        window.session.preset or None,
        tuple(window.session.available_methods()),
        window.files.suggested_name("mp4", "video"),
        window.settings,
        window.session.method,
        window.timeline.selection(),
    )


def add_menu_entries(window: StudioShell, file_menu: QMenu, action: Callable[..., QAction]) -> dict[str, QAction]:
    """Add New pose and Export video to ``file_menu`` with the menus' ``action`` helper."""
    return {
        "new_pose": action(window, file_menu, "&New pose...", lambda: new_pose(window), "Ctrl+Shift+N"),
        "export_video": action(window, file_menu, "Export &video...", lambda: export_video(window)),
    }
