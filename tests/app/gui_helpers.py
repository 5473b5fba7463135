"""Helpers of GUI tests: real input (Qt mouse events on the 3D view's native widget, as a
user's hand would send them; VTK display pixels, y up, converted to Qt's y down) and
closing a window at once."""

from __future__ import annotations

import numpy as np
from PyQt6.QtCore import QPointF, Qt
from PyQt6.QtGui import QMouseEvent
from PyQt6.QtWidgets import QApplication

LEFT = Qt.MouseButton.LeftButton
NONE = Qt.MouseButton.NoButton


def _send(widget, kind, x, y, button, buttons, mods):
    event = QMouseEvent(kind, QPointF(x, y), widget.mapToGlobal(QPointF(x, y)), button, buttons, mods)
    QApplication.sendEvent(widget, event)


def mouse_drag(
    view, start, end, ctrl: bool = False, steps: int = 6, alt: bool = False, on_move=None, shift: bool = False
) -> None:
    """Left-drag on the 3D view from ``start`` to ``end`` (VTK display pixels, y up),
    with Ctrl, Alt or Shift held; ``on_move()``, when given, is called after each move's events
    were processed (what the window holds in the middle of the drag: scripts/kill_test.py
    records it)."""
    widget = view.plotter
    h = widget.height()
    mods = Qt.KeyboardModifier.ControlModifier if ctrl else Qt.KeyboardModifier.NoModifier
    if alt:
        mods |= Qt.KeyboardModifier.AltModifier
    if shift:
        mods |= Qt.KeyboardModifier.ShiftModifier
    (x0, y0), (x1, y1) = start, end
    _send(widget, QMouseEvent.Type.MouseButtonPress, x0, h - 1 - y0, LEFT, LEFT, mods)
    for t in np.linspace(0, 1, steps + 1)[1:]:
        x, y = x0 + t * (x1 - x0), y0 + t * (y1 - y0)
        _send(widget, QMouseEvent.Type.MouseMove, x, h - 1 - y, NONE, LEFT, mods)
        QApplication.processEvents()
        if on_move is not None:
            on_move()
    _send(widget, QMouseEvent.Type.MouseButtonRelease, x1, h - 1 - y1, LEFT, NONE, mods)
    QApplication.processEvents()
    if on_move is not None:
        on_move()


def pixel_of(view, point) -> tuple[float, float]:
    x, y = view.joints._to_display(np.asarray(point, float)[None])[0]
    return float(x), float(y)


def close_now(w) -> None:
    """Close and delete the pose window ``w`` now, as the studio fixture does: a VTK view
    deleted later, among other tests' events, crashes."""
    from PyQt6.QtCore import QEvent

    w.session.history.set_clean()
    w.close()
    w.deleteLater()
    QApplication.sendPostedEvents(None, QEvent.Type.DeferredDelete.value)
