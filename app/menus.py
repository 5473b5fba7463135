"""The studio's menus: File, Edit (undo, redo, re-solve range, trim clip), Playback, View (display, camera) and Help.

Every entry is a QAction owned by the window, so its shortcut works anywhere in the
window and the help dialog can list it (:func:`app.menu_parts.shortcut_rows`).
"""

from __future__ import annotations

from typing import Any

from PyQt6.QtCore import Qt
from PyQt6.QtGui import QKeySequence
from PyQt6.QtWidgets import QMainWindow

from app import authoring_actions, clip_saving, clip_trim, range_actions
from app.menu_parts import action, add_view_entries, show_help, toggle
from app.undo import undo_actions


def build_menus(w: QMainWindow) -> None:
    """Fill ``w``'s menu bar; actions the tests and the help need are kept on ``w.actions_by_name``."""
    f = w.files
    named: dict[str, Any] = {}
    file_menu = w.menuBar().addMenu("&File")
    action(w, file_menu, "&Open motion (BVH / AMC)...", f.open_dialog, QKeySequence.StandardKey.Open)
    w.recent_menu = f.recent_menu = file_menu.addMenu("Open &recent")
    f.refresh_recent()
    named["connect_live"] = action(w, file_menu, "Connect &live source (VMC)...", w.live.connect_dialog)
    named["open_recording"] = action(w, file_menu, "Open &tracker recording...", w.live.open_recording_dialog)
    file_menu.addSeparator()
    action(w, file_menu, "&Save reconstruction (BVH / glTF)...", f.save_reconstruction, QKeySequence.StandardKey.Save)
    action(w, file_menu, "Save reconstruction onto the source &rig...", f.save_on_source_rig, "Ctrl+Alt+S")
    named.update(clip_saving.add_menu_entries(w, file_menu, action))
    action(w, file_menu, "Save s&cene...", f.save_scene, "Ctrl+Shift+S")
    action(w, file_menu, "&Load scene...", f.load_scene, "Ctrl+L")
    action(w, file_menu, "Export screens&hot...", f.export_screenshot, "Ctrl+E")
    named.update(authoring_actions.add_menu_entries(w, file_menu, action))
    file_menu.addSeparator()
    action(w, file_menu, "&Quit", w.close, QKeySequence.StandardKey.Quit)
    edit = w.menuBar().addMenu("&Edit")
    undo, redo = undo_actions(w, w.undo)
    undo.setShortcut(QKeySequence.StandardKey.Undo)
    redo.setShortcuts([QKeySequence("Ctrl+Shift+Z"), QKeySequence("Ctrl+Y")])
    for act in (undo, redo):
        act.setShortcutContext(Qt.ShortcutContext.WindowShortcut)
        edit.addAction(act)
    named["undo"], named["redo"] = undo, redo
    named.update(range_actions.add_edit_entries(w, edit, action))
    named.update(clip_trim.add_edit_entries(w, edit, action))
    play = w.menuBar().addMenu("&Playback")
    action(w, play, "Play / pause", w.toggle_play, "Space")
    action(w, play, "Next frame", lambda: w.session.step(1), "Right")
    action(w, play, "Previous frame", lambda: w.session.step(-1), "Left")
    view = w.menuBar().addMenu("&View")
    vp = w.viewport
    entries, camera = add_view_entries(w, view, "reconstruction", vp.set_display)
    named.update(entries)
    named["follow"] = toggle(w, camera, "F&ollow character", True, lambda v: setattr(vp, "follow", v), "F")
    view.addSeparator()
    toggle(w, view, "Ground truth", True, lambda v: setattr(vp, "show_ground_truth", v), "G")
    toggle(w, view, "Ghosts", True, lambda v: setattr(vp, "show_ghosts", v), "H")
    named.update(w.motion_paths.add_menu_entries(w, view))
    help_menu = w.menuBar().addMenu("&Help")
    named["help"] = action(
        w, help_menu, "&Keyboard and mouse...", lambda: show_help(w), QKeySequence.StandardKey.HelpContents
    )
    w.actions_by_name = named
