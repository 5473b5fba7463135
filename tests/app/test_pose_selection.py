"""Selecting and dragging in the pose window with real mouse events: a click selects a
joint, an Alt-drag that turns nothing leaves nothing, the constraints show their gizmos,
and a wrist dragged out sideways in the front view ends in a T-pose, not forward."""

from __future__ import annotations

import numpy as np
import pytest
from PyQt6.QtCore import Qt
from PyQt6.QtWidgets import QApplication

from engine import skeleton as sk
from tests.app.gui_helpers import LEFT, NONE, _send, mouse_drag, pixel_of
from widgets import style

pytestmark = pytest.mark.gui
LW, LE, LSH = (sk.JOINT_INDEX[j] for j in ("lwrist", "lelbow", "lshoulder"))


def click(view, x: float, y: float) -> None:
    """A left press and release at display pixel (x, y) (y up), no move between."""
    from PyQt6.QtGui import QMouseEvent

    widget, h = view.plotter, view.plotter.height()
    mods = Qt.KeyboardModifier.NoModifier
    _send(widget, QMouseEvent.Type.MouseButtonPress, x, h - 1 - y, LEFT, LEFT, mods)
    _send(widget, QMouseEvent.Type.MouseButtonRelease, x, h - 1 - y, LEFT, NONE, mods)
    QApplication.processEvents()


def test_a_click_on_a_joint_selects_it_and_its_rings_turn_it(pose_window):
    w = pose_window
    view = w.viewport
    view.plotter.render()
    click(view, *pixel_of(view, w.mode.pose.positions[LE]))
    assert w.selected == "lelbow" and view.rings.visible and view.rings.shown == (0, 1, 2)
    assert w.mode.targets == {} and w.undo.count() == 0, "a click moves nothing"
    # the rings are within reach at once: the Z ring dragged turns the elbow
    view.plotter.render()
    ring = view.joints._to_display(view.rings.meshes[2].points)
    far = ring[np.argmax(np.linalg.norm(ring - pixel_of(view, view.rings.center), axis=1))]
    mouse_drag(view, tuple(far), (far[0] + 25, far[1] + 25), steps=5)
    assert w.mode.targets["lelbow"].rotation is not None and w.undo.undo_text() == "turn lelbow"


def test_a_straight_alt_drag_leaves_no_target(pose_window, monkeypatch):
    """Alt + a drag straight away from the wrist asks for no turn: no '+rotation'
    target, no undo step; a drag that sweeps round the wrist turns it. Alt is read from
    the mouse events (the system's keys now may already be released: a busy machine
    handles them late)."""
    import app.pose_window as pw

    monkeypatch.setattr(pw.QApplication, "queryKeyboardModifiers", staticmethod(lambda: Qt.KeyboardModifier.NoModifier))
    w = pose_window
    view = w.viewport
    view.plotter.render()
    x, y = pixel_of(view, w.mode.pose.positions[LW])
    mouse_drag(view, (x, y), (x + 80, y), steps=8, alt=True)
    assert w.selected == "lwrist"
    assert "lwrist" not in w.mode.targets and w.undo.count() == 0
    assert "lwrist" not in w.targets.rows
    # sweeping round it does turn it (one step, shown as +rotation)
    view.plotter.render()
    x, y = pixel_of(view, w.mode.pose.positions[LW])
    mouse_drag(view, (x, y), (x + 60, y), steps=4, alt=True)
    mouse_drag(view, (x, y), (x + 5, y + 60), steps=2, alt=True)  # no pause: the same gesture goes on
    assert w.mode.targets["lwrist"].rotation is not None
    assert "+rotation" in w.targets.rows["lwrist"]["label"].text()


def gizmo_pixels(view) -> int:
    img = view.grab_image()
    ptr = img.constBits()
    ptr.setsize(img.sizeInBytes())
    a = np.frombuffer(ptr, np.uint8).reshape(img.height(), img.bytesPerLine())[:, : 3 * img.width()]
    rgb = a.reshape(img.height(), img.width(), 3).astype(int)
    return int((np.abs(rgb - style.hex_to_rgb(style.GIZMO)).sum(axis=2) < 40).sum())


def test_a_constraint_added_in_the_pose_window_shows_its_gizmo_and_its_handle_edits_it(pose_window):
    w = pose_window
    view, panel = w.viewport, w.constraints.panel
    view.plotter.render()
    assert gizmo_pixels(view) == 0
    panel.kinds.setCurrentText("look_at")
    panel.add_button.click()
    (look,) = w.mode.constraints
    assert look.name in view.gizmos.items
    view.plotter.render()
    assert gizmo_pixels(view) > 50, "the look-at's gizmo is on screen"
    handle = view.gizmos.items[look.name].widget
    x, y = pixel_of(view, handle.GetCenter())
    start = np.array(look.target, float)
    steps = w.undo.count()
    mouse_drag(view, (x, y), (x - 60, y + 30), steps=6)
    (moved,) = w.mode.constraints
    assert np.linalg.norm(np.asarray(moved.target) - start) > 0.05, "the handle moved the look-at's target"
    assert w.undo.count() == steps + 1 and w.mode.targets == {}, "one undo step, no joint dragged"
    w.session.undo()
    assert np.allclose(w.mode.constraints[0].target, start) and look.name in view.gizmos.items
    w.session.remove_constraint(look.name)
    assert view.gizmos.items == {}


def test_a_wrist_dragged_out_sideways_in_the_front_view_ends_in_a_t_pose(pose_window):
    """The mean pose's wrist hangs 21 cm in front of the shoulder: dragged in the front
    view to where a straight arm out to the side is on screen, the arm is straight out
    to the side there (it ended 25 degrees forward, at the depth the wrist hung at)."""
    w = pose_window
    view = w.viewport
    w.actions_by_name["camera-front"].trigger()
    p = w.mode.pose.positions
    arm = np.linalg.norm(p[LE] - p[LSH]) + np.linalg.norm(p[LW] - p[LE])
    assert p[LSH, 1] - p[LW, 1] > 0.15, "the wrist hangs in front of the shoulder"
    t_pose = p[LSH] + [arm, 0.0, 0.0]
    mouse_drag(view, pixel_of(view, p[LW]), pixel_of(view, t_pose), steps=20)
    q = w.mode.pose.positions
    out = q[LW] - q[LSH]
    forward = np.degrees(np.arctan2(-out[1], out[0]))
    assert abs(forward) < 8.0, f"the arm points {forward:.0f} degrees forward"
    assert np.linalg.norm(q[LW] - w.mode.targets["lwrist"].position) < 0.005, "the wrist reaches its target"
    np.testing.assert_allclose(pixel_of(view, q[LW]), pixel_of(view, t_pose), atol=3.0)
