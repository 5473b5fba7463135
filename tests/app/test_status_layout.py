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


def _message_area(bar) -> tuple[int, int]:
    """Where QStatusBar paints a message: from its 6 px margin to the first permanent widget."""
    right = bar.width() - 12
    permanent = [
        c for c in bar.findChildren(QWidget) if c.parent() is bar and c.isVisible() and c.x() > bar.width() // 2
    ]
    if permanent:
        right = min(c.x() for c in permanent) - 2
    return 6, right


def _covering(bar, text: str) -> list[tuple[str, str]]:
    """The visible status-bar widgets that lie over the first ``text``'s pixels."""
    left, right = _message_area(bar)
    end = left + min(bar.fontMetrics().horizontalAdvance(text), right - left)
    return [
        (type(c).__name__, c.text() if hasattr(c, "text") else "")
        for c in bar.findChildren(QWidget)
        if c.parent() is bar and c.isVisible() and c.x() < end and c.x() + c.width() > left
    ]


def test_a_message_shown_before_the_window_is_not_covered_once_it_shows(studio, qtbot):
    # The studio shows "Starting ..." and "Loaded FILE" before its window is on screen;
    # QStatusBar hides its readouts for a message only when they are visible then.
    studio.hide()
    bar = studio.statusBar()
    bar.showMessage("Loaded /home/user/clips/example.bvh (557 frames)", 15000)
    studio.show()
    _settle(qtbot)
    assert studio.status_engine.text(), "the solver readout has its figures (it would be drawn)"
    assert not _covering(bar, bar.currentMessage())
    bar.clearMessage()
    _settle(qtbot)
    assert studio.status_engine.isVisible() and studio.status_gui.isVisible()


def test_a_message_wider_than_the_bar_is_elided_with_the_whole_text_as_tooltip(studio, qtbot):
    bar = studio.statusBar()
    long = "Saved " + "/home/user/a-long-folder-name" * 12 + "/scene.json"
    bar.showMessage(long, 15000)
    _settle(qtbot)
    left, right = _message_area(bar)
    shown = bar.shown_message()
    assert shown != long and shown.endswith("…")
    assert bar.fontMetrics().horizontalAdvance(shown) <= right - left
    assert bar.toolTip() == long
    assert not _covering(bar, shown)
    bar.showMessage("Short", 15000)
    _settle(qtbot)
    assert bar.shown_message() == "Short" and bar.toolTip() == ""


def test_the_pose_window_elides_a_long_message_too(pose_window, qtbot):
    bar = pose_window.statusBar()
    long = "Scene written to " + "/home/user/a-long-folder-name" * 12 + "/pose.json"
    bar.showMessage(long, 5000)
    _settle(qtbot)
    assert bar.shown_message().endswith("…") and bar.toolTip() == long
