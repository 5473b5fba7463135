"""A pin added in the pose window where its joint is leaves the pose as it is (real
clicks on the Constraints dock's kind list and Add button). The pin's weight is 30, on
which fixed plain gradient steps overshoot: a pin on a stepped ankle, 6 mm from where
the latent puts that ankle, sends the loss from 0.03 to 4.8 in one step, the head 36 cm
away and a free arm up over the head unless the step is halved."""

from __future__ import annotations

import numpy as np
import pytest
from PyQt6.QtCore import Qt
from PyQt6.QtTest import QTest

from engine import skeleton as sk
from tests.app.gui_helpers import add_wrist_pin, mouse_drag, pixel_of

pytestmark = pytest.mark.gui

J = sk.JOINT_INDEX


def test_a_pin_added_on_a_stepped_foot_moves_nothing(pose_window):
    w = pose_window
    v = w.viewport
    v.set_camera("front", w.hips())
    v.plotter.render()
    p = w.mode.pose.positions.copy()
    mouse_drag(v, pixel_of(v, p[J["rwrist"]]), pixel_of(v, p[J["rshoulder"]] + [-0.1, 0.0, 0.35]), steps=8)
    w.add_key(0)  # a raised hand keyed at 0 ...
    w.session.set_length(200)
    w.go_to(191)  # ... held after it: a step made there
    v.set_camera("side", w.hips())
    v.plotter.render()
    p = w.mode.pose.positions.copy()
    mouse_drag(v, pixel_of(v, p[J["lankle"]]), pixel_of(v, p[J["lankle"]] + [0.0, -0.3, 0.0]), steps=8)
    w.add_key(191)
    before = w.mode.pose.positions.copy()
    panel = w.constraints.panel
    panel.kinds.setCurrentText("pin")
    QTest.mouseClick(panel.add_button, Qt.MouseButton.LeftButton)
    (pin,) = w.mode.constraints
    assert pin.kind == "pin" and pin.joint == "lankle"
    moved = np.linalg.norm(w.mode.pose.positions - before, axis=1)
    assert moved.max() < 0.03, f"{sk.JOINT_NAMES[int(moved.argmax())]} moved {moved.max():.3f} m"
    assert np.linalg.norm(w.mode.pose.positions[J["lankle"]] - pin.position) < 0.01


def test_a_pin_put_on_another_joint_in_its_editor_pins_that_joint_where_it_is(pose_window):
    """A pin is added on the ankle (its default joint); choosing the wrist in its editor
    pins the wrist where the wrist is. Left at the ankle's place, the pin pulls the wrist
    down to the floor and folds the body over."""
    w = pose_window
    before = w.mode.pose.positions.copy()
    pin = add_wrist_pin(w)
    assert np.linalg.norm(pin.position - before[J["lwrist"]]) < 1e-6
    moved = np.linalg.norm(w.mode.pose.positions - before, axis=1)
    assert moved.max() < 0.02, f"{sk.JOINT_NAMES[int(moved.argmax())]} moved {moved.max():.3f} m"
    w.undo.undo()  # one step: the joint and the place together
    assert w.mode.constraints[0].joint == "lankle"


def test_the_constraint_list_names_a_pin_s_joint_and_frames(pose_window):
    """Each row of the Constraints list says what its constraint holds and when: a pin
    added with the dock and put on the left wrist read *pin [pin]* whichever joint it
    held and whatever its range, so two pins could not be told apart."""
    w = pose_window
    w.session.set_length(200)
    pin = add_wrist_pin(w)
    rows = w.constraints.panel.list
    assert "lwrist" in rows.item(0).text()
    w.session.update_constraint(pin.name, {"frames": (100, 160)})
    assert "lwrist" in rows.item(0).text() and "100-160" in rows.item(0).text()
