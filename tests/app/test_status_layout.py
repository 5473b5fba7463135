"""Status messages move nothing and are read whole: the pose window's first message does
not push its 3D view and key timeline up, and the studio's solver readouts give way to a
message instead of cutting it off."""

from __future__ import annotations

import pytest
from PyQt6.QtCore import QPoint
from PyQt6.QtWidgets import QApplication, QWidget

pytestmark = pytest.mark.gui

LONG = (
    "Loaded pose.json: replaced the constraints (1) and the optimizer settings (32); kept the sensors and "
    "preset (the scene has none)"
)


def _settle(qtbot) -> None:
    for _ in range(3):
        QApplication.processEvents()
        qtbot.wait(20)


def _place(w, widget) -> tuple[int, int, int, int]:
    top_left = widget.mapTo(w, QPoint(0, 0))
    return top_left.x(), top_left.y(), widget.width(), widget.height()


def test_the_first_status_message_moves_nothing_in_the_pose_window(pose_window, qtbot):
    w = pose_window
    _settle(qtbot)
    before = {"view": _place(w, w.viewport), "keys": _place(w, w.keys)}
    w.statusBar().showMessage("Scene written to /home/user/pose.json", 5000)
    _settle(qtbot)
    after = {"view": _place(w, w.viewport), "keys": _place(w, w.keys)}
    assert after == before


def test_a_long_status_message_in_the_studio_is_not_cut_off_by_the_solver_readouts(studio, qtbot):
    studio.resize(1280, 800)
    _settle(qtbot)
    bar = studio.statusBar()
    assert studio.status_engine.isVisible()
    bar.showMessage(LONG, 15000)
    _settle(qtbot)
    text_end = bar.fontMetrics().horizontalAdvance(LONG) + 8  # Qt's left margin
    covering = [
        (type(c).__name__, c.geometry().x())
        for c in bar.findChildren(QWidget)
        if c.parent() is bar and c.isVisible() and c.geometry().x() < text_end
    ]
    assert not covering, f"the message ends at x={text_end}; over it: {covering}"
    bar.clearMessage()
    _settle(qtbot)
    assert studio.status_engine.isVisible()  # the readouts are back once the message is gone
