"""Saving the studio's authoring edits: the edited clip as BVH or glTF, and the unsaved-changes prompt.

A range re-solve (Edit ▸ Re-solve range) or a trim (Edit ▸ Trim clip to selection)
replaces the loaded clip in memory; File ▸ Save
edited clip writes it as it is now, on the canonical skeleton or onto the rig of
the file it was opened from (:func:`engine.motion.write_back.save_on_source_rig`),
atomically, with no solver run (the reconstruction saves re-solve the clip instead).

The window's undo history says what is unsaved: any edit since the clip was opened or the
scene saved or loaded (range re-solves, constraint and sensor edits) leaves it unclean,
and quitting or opening another clip or scene then asks Save / Discard / Cancel. Save
writes the scene and, when the clip was re-solved, the edited clip.
"""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

from PyQt6.QtGui import QAction
from PyQt6.QtWidgets import QMenu, QMessageBox

from app.motion_files import ask_motion_path
from app.shell import StudioShell
from engine.errors import UserError


def clip_edited(window: StudioShell) -> bool:
    """Whether the loaded clip differs from the one opened (a range re-solve or a trim not undone)."""
    session = window.session
    opened = window.opened_motion
    return session.motion is not None and opened is not None and session.motion is not opened


def edit_kind(window: StudioShell) -> str:
    """How the loaded clip was edited, for the prompt: ``trimmed`` (fewer frames than
    opened, re-solved or not) or ``re-solved``."""
    opened, motion = window.opened_motion, window.session.motion
    trimmed = opened is not None and motion is not None and len(motion) != len(opened)
    return "trimmed" if trimmed else "re-solved"


def save_clip(window: StudioShell, path: str | Path, on_source_rig: bool = False) -> str:
    """Write the loaded clip as it is now to ``path`` (BVH or glTF by the extension, atomically): on the canonical
    skeleton, or with ``on_source_rig`` onto the hierarchy of the file it was opened from. Returns what the
    file lacks of the source, for the message that says it was written (:func:`engine.studio.export.skipped_note`).

    Raises
    ------
    UserError
        With no clip, or ``on_source_rig`` for a clip not opened from a file (or a rig
        whose channels cannot be written back).
    """
    from engine.studio.export import skipped_note, source_rig, write_reconstruction

    session = window.session
    if session.motion is None or session.source is not None:
        raise UserError("open a clip first")
    if on_source_rig and session.path is None:
        raise UserError("this clip was not opened from a BVH file")
    on_rig = source_rig(session.path, session.rig_map) if on_source_rig else None
    write_reconstruction(path, session.motion, on_rig)
    return skipped_note(on_rig[1], session.motion.start / session.motion.fps) if on_rig is not None else ""


def save_clip_dialog(window: StudioShell, on_source_rig: bool = False) -> bool:
    """Ask for a file and save the clip there; False when cancelled or failed."""
    title = "Save edited clip" + (" onto the source rig" if on_source_rig else "")
    path = ask_motion_path(window, title, window.files.suggested_name("bvh", "edited"), window.settings)
    if not path:
        return False
    try:
        note = save_clip(window, path, on_source_rig)
    except (UserError, OSError) as exc:
        window.show_error("Cannot save the clip", str(exc))
        return False
    window.statusBar().showMessage(f"Saved the clip to {path}{note}", 15000)
    return True


def save_edits(window: StudioShell) -> bool:
    """Save the edited clip (if re-solved) and the scene, each asking for a file; the
    edits then count as saved. False when a save was cancelled or failed."""
    if clip_edited(window) and not save_clip_dialog(window):
        return False
    if not window.files.save_scene():
        return False
    window.undo.set_clean()
    return True


def confirm_discard(window: StudioShell, doing: str) -> bool:
    """Before ``doing`` (``"quitting"``, ``"opening another clip"``...): True when there
    is nothing unsaved, or the user saved or discarded it; False to stay (Cancel)."""
    if window.undo.is_clean():
        return True
    buttons = QMessageBox.StandardButton
    what = f"the {edit_kind(window)} clip and the scene" if clip_edited(window) else "the scene"
    answer = QMessageBox.question(
        window,
        "Unsaved changes",
        f"Save the edits of {what} before {doing}?",
        buttons.Save | buttons.Discard | buttons.Cancel,
    )
    if answer == buttons.Save:
        return save_edits(window)
    return answer == buttons.Discard


def add_menu_entries(window: StudioShell, file_menu: QMenu, action: Callable[..., QAction]) -> dict[str, QAction]:
    """Add the edited clip's saves to ``file_menu`` with the menus' ``action`` helper."""
    return {
        "save_clip": action(window, file_menu, "Save edited &clip (BVH / glTF)...", lambda: save_clip_dialog(window)),
        "save_clip_rig": action(
            window, file_menu, "Save edited clip onto the source r&ig...", lambda: save_clip_dialog(window, True)
        ),
    }
