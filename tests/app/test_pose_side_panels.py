"""The pose window's side panels keep what a user needs in sight: with the three targets of
a T-pose with the head turned (real drags), every target row and Clear all are on screen
without scrolling the Targets panel."""

from __future__ import annotations

import pytest
from PyQt6.QtCore import QPoint, QRect

from engine import skeleton as sk
from tests.app.gui_helpers import mouse_drag, pixel_of

pytestmark = pytest.mark.gui


def on_screen(widget, scroll) -> bool:
    """Whether ``widget`` lies wholly inside the visible part of the scroll area ``scroll``."""
    viewport = scroll.viewport()
    top_left = widget.mapTo(viewport, QPoint(0, 0))
    return widget.isVisible() and viewport.rect().contains(QRect(top_left, widget.size()))


def test_three_targets_and_clear_all_are_in_sight_without_scrolling(pose_window, qtbot):
    w = pose_window
    qtbot.wait(50)
    w.viewport.plotter.render()
    for joint in ("lwrist", "rwrist", "upperneck"):
        x, y = pixel_of(w.viewport, w.mode.pose.positions[sk.JOINT_INDEX[joint]])
        mouse_drag(w.viewport, (x, y), (x + 12, y + 8), steps=2)
        assert joint in w.mode.targets
        w.viewport.plotter.render()
    qtbot.wait(50)
    scroll = w.targets.parentWidget().parentWidget()  # the dock's scroll area (viewport > widget)
    assert scroll.verticalScrollBar().value() == 0
    assert on_screen(w.targets.clear_all, scroll)
    for joint, row in w.targets.rows.items():
        assert on_screen(row["clear"], scroll) and on_screen(row["weight"], scroll), joint
