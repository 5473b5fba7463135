"""Parts of the menus that the studio and the pose window share: the action and toggle
helpers, the camera entries and the help dialog that lists every shortcut.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

from PyQt6 import sip
from PyQt6.QtCore import QObject, Qt
from PyQt6.QtGui import QAction, QActionGroup, QKeySequence
from PyQt6.QtWidgets import QMenu

from app.shell import ViewWindow
from widgets.help_dialog import HelpDialog

#: View ▸ Camera entries: preset, label, shortcut (Blender's numpad digits).
CAMERAS = (
    ("home", "&Home (front-left)", "Home"),
    ("front", "&Front", "1"),
    ("side", "&Side (character's left)", "3"),
    ("top", "&Top", "7"),
)


def action(window: QObject, menu: QMenu, text: str, slot: Callable[[], Any], shortcut: Any = None) -> QAction:
    act = QAction(text, window)
    if shortcut is not None:
        act.setShortcut(QKeySequence(shortcut))
        act.setShortcutContext(Qt.ShortcutContext.WindowShortcut)
    act.triggered.connect(lambda _=False: slot())
    menu.addAction(act)
    return act


def toggle(
    window: QObject, menu: QMenu, text: str, on: bool, slot: Callable[[bool], Any], shortcut: str | None = None
) -> QAction:
    act = QAction(text, window, checkable=True, checked=on)
    if shortcut:
        act.setShortcut(QKeySequence(shortcut))
        act.setShortcutContext(Qt.ShortcutContext.WindowShortcut)
    act.toggled.connect(slot)
    menu.addAction(act)
    return act


def add_view_entries(w: ViewWindow, view: QMenu, noun: str, set_display: Callable[[str], Any]) -> tuple[dict, QMenu]:
    """View ▸ Draw ``noun`` as (stick figure S, shaded body B) and View ▸ Camera (the
    :data:`CAMERAS` presets about ``w.hips()``) on ``view``; the actions by name and the
    camera menu, for the window's own camera entries."""
    named: dict[str, QAction] = {}
    vp = w.viewport
    display = view.addMenu(f"&Draw {noun} as")
    group = QActionGroup(w)
    for mode, label, key in (("stick", "&Stick figure", "S"), ("body", "Shaded &body", "B")):
        act = toggle(w, display, label, vp.display == mode, lambda on, m=mode: on and set_display(m), key)
        group.addAction(act)
        named[f"display-{mode}"] = act
    camera = view.addMenu("&Camera")
    for preset, label, key in CAMERAS:
        named[f"camera-{preset}"] = action(w, camera, label, lambda p=preset: vp.set_camera(p, w.hips()), key)
    return named, camera


def shortcut_rows(w: ViewWindow) -> list[tuple[str, str]]:
    """``(shortcut, menu path)`` of every window action that has a shortcut."""
    rows = []

    def walk(menu: QMenu, path: str) -> None:
        for act in menu.actions():
            if act.menu() is not None:
                walk(act.menu(), f"{path} > {act.text().replace('&', '')}")
            elif not act.isSeparator() and not act.shortcut().isEmpty():
                keys = act.shortcut().toString(QKeySequence.SequenceFormat.NativeText)
                rows.append((keys, f"{path} > {act.text().replace('&', '').rstrip('.')}"))

    for top in w.menuBar().actions():
        if top.menu() is not None:
            walk(top.menu(), top.text().replace("&", ""))
    return rows


def show_help(w: ViewWindow) -> HelpDialog:
    """Show the window's shortcut list, raising the one already open (a second F1 made a
    second window, and every one stayed, hidden behind, until the window closed)."""
    dialog = getattr(w, "help_dialog", None)
    if dialog is None or sip.isdeleted(dialog):
        dialog = HelpDialog(shortcut_rows(w), w, w.mouse_help)
        dialog.setModal(False)
        dialog.setAttribute(Qt.WidgetAttribute.WA_DeleteOnClose)
        w.help_dialog = dialog
    dialog.show()
    dialog.raise_()
    return dialog
