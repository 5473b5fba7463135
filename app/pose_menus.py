"""The pose window's menus: File (new pose, scenes, exports), Edit (undo, redo, settle, clear), Keys (play, step,
add and delete keys), View (display, camera, naturalness reference) and Help, built with the studio's helpers so
the same keys do the same things in both.

Every entry is a QAction owned by the window (a QAction that only a local variable
holds is deleted by PyQt and drops out of its menu), kept on ``w.actions_by_name`` for
the tests and the help. Undo and Redo call the authoring model; the window keeps their
text and enabled state in step with the model's history.
"""

from __future__ import annotations

from typing import Any

from PyQt6.QtGui import QKeySequence
from PyQt6.QtWidgets import QMainWindow

from app.menu_parts import action, add_view_entries, show_help, toggle
from app.pose_naturalness import ReferenceMenu


def build_pose_menus(w: QMainWindow) -> None:
    """Fill the pose window ``w``'s menu bar (see the module doc)."""
    named: dict[str, Any] = {}
    file_menu = w.menuBar().addMenu("&File")
    f = w.files
    named["new_pose"] = action(w, file_menu, "&New pose...", f.new_dialog, "Ctrl+Shift+N")
    named["open"] = action(w, file_menu, "&Open scene...", f.open_dialog, QKeySequence.StandardKey.Open)
    named["save"] = action(w, file_menu, "&Save scene...", f.save_dialog, QKeySequence.StandardKey.Save)
    named["export_bvh"] = action(w, file_menu, "Export &motion (BVH / glTF)...", f.export_bvh_dialog, "Ctrl+B")
    named["export_video"] = action(w, file_menu, "Export &video...", f.export_video_dialog)
    file_menu.addSeparator()
    named["close"] = action(w, file_menu, "&Close", w.close, QKeySequence.StandardKey.Close)
    edit = w.menuBar().addMenu("&Edit")
    # undo and redo go through the model; the window names the step on its history event
    undo = action(w, edit, "&Undo", w.undo_step, QKeySequence.StandardKey.Undo)
    redo = action(w, edit, "&Redo", lambda: w.undo_step(redo=True))
    redo.setShortcuts([QKeySequence("Ctrl+Shift+Z"), QKeySequence("Ctrl+Y")])
    named["undo"], named["redo"] = undo, redo
    edit.addSeparator()
    named["settle"] = action(w, edit, "S&ettle pose", w.settle, "Ctrl+Return")
    named["clear_all"] = action(w, edit, "&Clear all targets (reset pose)", w.clear_all, "Ctrl+Shift+Delete")
    named["deselect"] = action(w, edit, "&Hide the rotation rings", w.deselect, "Escape")
    keys = w.menuBar().addMenu("&Keys")
    named["play"] = action(w, keys, "&Play / stop", lambda: w.keys.previewRequested.emit(), "Space")
    named["next_frame"] = action(w, keys, "&Next frame", lambda: w.step(1), "Right")
    named["previous_frame"] = action(w, keys, "P&revious frame", lambda: w.step(-1), "Left")
    named["next_key"] = action(w, keys, "Next &key", lambda: w.step_key(1), "Ctrl+Right")
    named["previous_key"] = action(w, keys, "Previous k&ey", lambda: w.step_key(-1), "Ctrl+Left")
    named["add_key"] = action(w, keys, "&Add key at the current frame", lambda: w.add_key(w.frame), "K")
    named["delete_key"] = action(
        w, keys, "&Delete the key at the current frame", lambda: w.delete_key(w.frame), "Shift+K"
    )
    named["loop"] = toggle(w, keys, "&Loop playing", False, w.keys.loop.setChecked, "L")
    w.keys.loop.toggled.connect(named["loop"].setChecked)
    view = w.menuBar().addMenu("&View")
    vp = w.viewport
    entries, camera = add_view_entries(w, view, "character", w.set_display)
    named.update(entries)
    # F frames the character (as in Maya): a camera that followed every edit would move
    # under a drag, and the drag plane with it
    named["frame"] = action(w, camera, "F&rame the character", lambda: vp.frame(w.hips()), "F")
    named.update(w.paths.add_menu_entries(w, view))
    w.reference_menu = ReferenceMenu(w, view)
    named["reference_shipped"], named["reference_files"] = w.reference_menu.shipped, w.reference_menu.files
    help_menu = w.menuBar().addMenu("&Help")
    named["help"] = action(
        w, help_menu, "&Keyboard and mouse...", lambda: show_help(w), QKeySequence.StandardKey.HelpContents
    )
    w.actions_by_name = named
