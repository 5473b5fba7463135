"""Fields the user types into while the engine keeps refreshing the panels.

Two rules, shared by the optimizer panel and the constraint editor: a number is sent
once, when it is committed (Return, Tab, focus lost, or a step of the arrows or wheel),
never for each key; and a refresh never writes into a field the user is in, since that
replaces the half-typed text (``0.`` of ``0.02``) and the keys that follow are lost.
"""

from __future__ import annotations

from PyQt6.QtWidgets import QAbstractButton, QAbstractSpinBox, QApplication, QComboBox, QWidget


def commit_only(spin: QAbstractSpinBox) -> QAbstractSpinBox:
    """``spin`` emitting ``valueChanged`` on commit only, not while a number is typed."""
    spin.setKeyboardTracking(False)
    return spin


def is_editing(w: QWidget) -> bool:
    """The user is in ``w``: it or one of its children (a spin box's line edit, one of a
    vector's spin boxes) has the keyboard focus, or its drop-down list is open. A check box
    or button never is: its click is sent at once and nothing half-done waits in it, so an
    undo or a scene load must show there even while it keeps the focus."""
    if isinstance(w, QAbstractButton):
        return False
    focus = QApplication.focusWidget()
    if focus is not None and (focus is w or w.isAncestorOf(focus)):
        return True
    return isinstance(w, QComboBox) and w.view().isVisible()
