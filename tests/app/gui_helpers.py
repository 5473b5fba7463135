"""Helpers of GUI tests: real input (Qt mouse events on the 3D view's native widget, as a
user's hand would send them; VTK display pixels, y up, converted to Qt's y down; clicks on
the pose window's key timeline; shortcuts) and closing a window at once."""

from __future__ import annotations

import numpy as np
from PyQt6.QtCore import QPoint, QPointF, Qt
from PyQt6.QtGui import QMouseEvent
from PyQt6.QtTest import QTest
from PyQt6.QtWidgets import QApplication, QComboBox

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


def on_screen(view) -> np.ndarray:
    """The 3D view's pixels as the X server has them (not a render VTK would make for a
    screenshot): (h, w, 3) uint8."""
    from PyQt6.QtGui import QGuiApplication

    view.plotter.render_window.WaitForCompletion()
    shot = QGuiApplication.primaryScreen().grabWindow(int(view.plotter.winId())).toImage()
    shot = shot.convertToFormat(shot.Format.Format_RGB888)
    w, h = shot.width(), shot.height()
    img = np.frombuffer(shot.constBits().asstring(shot.bytesPerLine() * h), np.uint8)
    return img.reshape(h, shot.bytesPerLine())[:, : 3 * w].reshape(h, w, 3).copy()


def _mods(ctrl: bool) -> Qt.KeyboardModifier:
    return Qt.KeyboardModifier.ControlModifier if ctrl else Qt.KeyboardModifier.NoModifier


def mouse_press(view, at, ctrl: bool = False) -> None:
    """Press the left button on the 3D view at ``at`` (VTK display pixels, y up)."""
    widget = view.plotter
    _send(widget, QMouseEvent.Type.MouseButtonPress, at[0], widget.height() - 1 - at[1], LEFT, LEFT, _mods(ctrl))
    QApplication.processEvents()


def mouse_move(view, to, ctrl: bool = False) -> None:
    """Move the mouse, the left button held, to ``to`` (VTK display pixels, y up)."""
    widget = view.plotter
    _send(widget, QMouseEvent.Type.MouseMove, to[0], widget.height() - 1 - to[1], NONE, LEFT, _mods(ctrl))
    QApplication.processEvents()


def mouse_release(view, at, ctrl: bool = False) -> None:
    """Let go of the left button at ``at`` (VTK display pixels, y up)."""
    widget = view.plotter
    _send(widget, QMouseEvent.Type.MouseButtonRelease, at[0], widget.height() - 1 - at[1], LEFT, NONE, _mods(ctrl))
    QApplication.processEvents()


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


def scrub(w, frame: int) -> None:
    """A click on the pose window ``w``'s key timeline at ``frame``."""
    strip = w.keys.strip
    QTest.mouseClick(strip, LEFT, pos=QPoint(round(strip.x_of(frame)), strip.height() // 2))
    QApplication.processEvents()


def drag_on_strip(w, frame: int, to: int) -> None:
    """A left-drag along the pose window ``w``'s key timeline from ``frame`` to ``to``."""
    strip = w.keys.strip
    y = strip.height() // 2
    QTest.mousePress(strip, LEFT, pos=QPoint(round(strip.x_of(frame)), y))
    for t in np.linspace(0, 1, 5)[1:]:
        x = round(strip.x_of(frame) + t * (strip.x_of(to) - strip.x_of(frame)))
        _send(strip, QMouseEvent.Type.MouseMove, x, y, NONE, LEFT, Qt.KeyboardModifier.NoModifier)
    QTest.mouseRelease(strip, LEFT, pos=QPoint(round(strip.x_of(to)), y))
    QApplication.processEvents()


def drag_wrist(w) -> None:
    """A drag of the pose window ``w``'s left wrist up and to the side."""
    from engine import skeleton as sk

    view = w.viewport
    view.plotter.render()
    x, y = pixel_of(view, w.mode.pose.positions[sk.JOINT_INDEX["lwrist"]])
    mouse_drag(view, (x, y), (x + 50, y + 90), steps=6)


def shortcut(w, key: Qt.Key, mods=Qt.KeyboardModifier.ControlModifier) -> None:
    """``key`` with ``mods`` pressed where the keyboard focus is (else on ``w``)."""
    QTest.keyClick(QApplication.focusWidget() or w, key, mods)
    QApplication.processEvents()


def type_number(spin, value: int) -> None:
    """Click into a spin box, type ``value`` and commit it with Return, as a user does."""
    spin.setFocus()
    QApplication.processEvents()
    spin.selectAll()
    QTest.keyClicks(spin, str(value))
    QTest.keyClick(spin, Qt.Key.Key_Return)
    QApplication.processEvents()


def add_wrist_pin(w):
    """A pin added with the pose window's Constraints dock (on the joint last clicked, or
    its default joint) and put on the left wrist in its editor."""
    panel = w.constraints.panel
    panel.kinds.setCurrentText("pin")
    QTest.mouseClick(panel.add_button, Qt.MouseButton.LeftButton)
    (added,) = w.mode.constraints
    (joint_box,) = [b for b in panel.editor.findChildren(QComboBox) if b.currentText() == added.joint]
    joint_box.setCurrentText("lwrist")
    (pin,) = w.mode.constraints
    assert pin.joint == "lwrist"
    return pin


def ctrl_drag_pin(studio, qtbot, frame: int = 50, joint: str = "lelbow"):
    """Pause the studio on ``frame``, Ctrl-drag ``joint`` 40 px right and 10 down in its
    viewport (a pin where the drag ends) and return the constraint it made."""
    from engine import skeleton as sk

    view, s = studio.viewport, studio.session
    s.seek(frame)
    s.pause()
    qtbot.waitUntil(lambda: not s.latest.playing and s.latest.frame == frame, timeout=10000)
    view.show_snapshot(s.latest)
    x, y = pixel_of(view, s.latest.positions[sk.JOINT_INDEX[joint]])
    mouse_drag(view, (x, y), (x + 40, y + 10), ctrl=True)
    qtbot.waitUntil(lambda: len(s.constraints) == 1, timeout=5000)
    return s.constraints[0]
