"""The camera keys (Home, 1, 3, 7) work wherever the keyboard focus is, except in a field
the user types into.

Qt lets the focused widget override a shortcut: a slider takes Home, a combo box takes
digits for its keyboard search, so after a click in a panel the camera keys did nothing
until the user clicked the 3D view. This filter lets the View ▸ Camera shortcuts fire
whatever has the focus, unless it is a text or number field: typing 0.3 must give 0.3
wherever the pointer rests. Escape, a click on the view, and Return or Enter in a
one-line field (once the field has taken the value) give the keys back: left in a number
field after Return, the focus would take a 1 pressed next for the front view, and a
length of 200 would become 1 frame.
"""

from __future__ import annotations

from PyQt6.QtCore import QEvent, QObject, Qt, QTimer
from PyQt6.QtGui import QKeyEvent
from PyQt6.QtWidgets import QAbstractSpinBox, QApplication, QComboBox, QLineEdit, QPlainTextEdit, QTextEdit, QWidget

#: Keys of View ▸ Camera (:data:`app.menu_parts.CAMERAS`) that no other panel widget keeps.
CAMERA_KEYS = frozenset((Qt.Key.Key_Home, Qt.Key.Key_1, Qt.Key.Key_3, Qt.Key.Key_7))


def types_text(widget: QWidget | None) -> bool:
    """Whether ``widget`` is a field whose keys are text (line edits, number fields,
    editable combo boxes, text areas)."""
    if isinstance(widget, QComboBox):
        return widget.isEditable()
    return isinstance(widget, (QLineEdit, QAbstractSpinBox, QTextEdit, QPlainTextEdit))


class CameraKeys(QObject):
    """Application event filter: a camera key that the focused widget would override
    reaches the View ▸ Camera shortcut instead, unless that widget types text."""

    def __init__(self, view: QWidget, parent: QObject | None = None) -> None:
        super().__init__(parent)
        self._view = view

    def eventFilter(self, obj: QObject | None, event: QEvent | None) -> bool:
        if (
            event is not None
            and event.type() == QEvent.Type.KeyPress
            and isinstance(event, QKeyEvent)
            and event.key() == Qt.Key.Key_Escape
            and obj is QApplication.focusWidget()
            and types_text(obj)
            and obj.window() is self._view.window()
        ):
            self._view.setFocus()  # leave the field: the camera keys are the view's again
            return True
        if (
            event is not None
            and event.type() == QEvent.Type.KeyPress
            and isinstance(event, QKeyEvent)
            and event.key() in (Qt.Key.Key_Return, Qt.Key.Key_Enter)
            and obj is QApplication.focusWidget()
            and types_text(obj)
            and not isinstance(obj, (QTextEdit, QPlainTextEdit))
            and obj.window() is self._view.window()
        ):
            # the field takes the Return (its value is set), then the view takes the focus
            QTimer.singleShot(0, self._view.setFocus)
            return False
        if event is not None and event.type() == QEvent.Type.ShortcutOverride and isinstance(event, QKeyEvent):
            mods = event.modifiers() & ~Qt.KeyboardModifier.KeypadModifier
            if event.key() in CAMERA_KEYS and mods == Qt.KeyboardModifier.NoModifier:
                focus = QApplication.focusWidget()
                if types_text(focus) or (focus is not None and focus.window() is not self._view.window()):
                    return False  # a field being typed in, or another window's widget
                event.ignore()  # not overridden: the shortcut map fires the camera action
                return True
        return False
