"""The camera keys (Home, 1, 3, 7) reach the 3D view while the pointer is over it.

A number field that has the keyboard focus takes digits and Home for itself (Qt lets
the focused widget override a shortcut), so after an edit in a panel the camera keys
did nothing until the user clicked the view. While the pointer is over the 3D view
those keys go to its camera, whatever has the focus; elsewhere a number field keeps
its digits (typing 0.3 must stay possible).
"""

from __future__ import annotations

from PyQt6.QtCore import QEvent, QObject, Qt
from PyQt6.QtGui import QCursor, QKeyEvent
from PyQt6.QtWidgets import QWidget

#: Keys of View ▸ Camera (:data:`app.menus.CAMERAS`) the 3D view takes from a field.
CAMERA_KEYS = frozenset((Qt.Key.Key_Home, Qt.Key.Key_1, Qt.Key.Key_3, Qt.Key.Key_7))


class CameraKeys(QObject):
    """Application event filter: a camera key pressed with the pointer over ``view``
    is not overridden by the focused widget, so the View ▸ Camera shortcut fires."""

    def __init__(self, view: QWidget, parent: QObject | None = None) -> None:
        super().__init__(parent)
        self._view = view

    def pointer_over_view(self) -> bool:
        view = self._view
        return view.isVisible() and view.rect().contains(view.mapFromGlobal(QCursor.pos()))

    def eventFilter(self, obj: QObject | None, event: QEvent | None) -> bool:
        if event is not None and event.type() == QEvent.Type.ShortcutOverride and isinstance(event, QKeyEvent):
            mods = event.modifiers() & ~Qt.KeyboardModifier.KeypadModifier
            if event.key() in CAMERA_KEYS and mods == Qt.KeyboardModifier.NoModifier and self.pointer_over_view():
                event.ignore()  # not overridden: the shortcut map fires the camera action
                return True
        return False
