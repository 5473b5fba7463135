"""Constraint editing end to end: a stand-in kind for the editor mechanics, the real pin for Ctrl-drag."""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar

import numpy as np
import pytest

from engine import skeleton as sk
from engine.constraints.base import REGISTRY, Constraint, param
from engine.constraints.placement import LOOK_DISTANCE
from engine.gizmos import PointGizmo

pytestmark = pytest.mark.gui


@pytest.fixture
def pin_kind():
    @dataclass
    class StudioTestPin(Constraint):
        kind: ClassVar[str] = "studio_test_pin"
        joint: str = param("lwrist", editor="joint")
        target: np.ndarray = param(factory=lambda: np.array([0.3, -0.2, 1.2]), editor="vec3", unit="m")

        def acts_on(self):
            return (self.joint,)

        @classmethod
        def placement(cls, params, positions):
            return {}

        def term(self, frame):
            from engine.constraints.pin import PinConstraint

            return PinConstraint(name=self.name, joint=self.joint, position=self.target).term(frame)

        @classmethod
        def examples(cls, positions):
            return [cls()]

        def gizmo(self, positions=None):
            return PointGizmo(self.target, edit="target")

    yield StudioTestPin.kind
    REGISTRY.pop(StudioTestPin.kind, None)  # keep the registry as other tests expect it


def test_add_edit_drag_disable_and_remove_a_constraint(pin_kind, studio, qtbot):
    panel, session = studio.constraint_panel, studio.session
    panel.kinds.setCurrentText(pin_kind)
    panel.add_button.click()
    name = session.constraints[0].name
    qtbot.waitUntil(lambda: name in studio.viewport.gizmos.items)

    widget = studio.viewport.gizmos.items[name].widget
    widget.InvokeEvent("StartInteractionEvent")
    widget.SetCenter(0.5, 0.0, 1.0)
    widget.InvokeEvent("InteractionEvent")
    widget.InvokeEvent("EndInteractionEvent")
    assert np.allclose(session.constraints[0].target, [0.5, 0.0, 1.0])
    qtbot.waitUntil(lambda: np.allclose(dict(studio.session.latest.gizmos)[name].position, [0.5, 0, 1]))

    panel.editor.inputs["target"].spins[2].setValue(1.4)
    panel.editor.inputs["weight"].setValue(3.0)
    assert session.constraints[0].target[2] == pytest.approx(1.4) and session.constraints[0].weight == 3.0

    from PyQt6.QtCore import Qt

    panel.list.item(0).setCheckState(Qt.CheckState.Unchecked)
    assert session.constraints[0].enabled is False
    qtbot.waitUntil(lambda: name not in dict(studio.session.latest.gizmos))
    panel.remove_button.click()
    assert list(session.constraints) == [] and panel.list.count() == 0


def test_ctrl_dragging_a_joint_without_sensor_pins_it(studio, qtbot):
    studio.viewport.jointDragged.emit("lelbow", np.array([0.4, 0.0, 1.3]))
    (pin,) = studio.session.constraints
    assert pin.kind == "pin" and pin.joint == "lelbow" and np.allclose(pin.position, [0.4, 0, 1.3])
    studio.viewport.jointDragged.emit("lelbow", np.array([0.5, 0.0, 1.3]))
    (moved,) = studio.session.constraints  # an edit replaces the object (engine.studio.session)
    assert moved.name == pin.name and np.allclose(moved.position, [0.5, 0, 1.3])


@pytest.mark.parametrize("kind", ["bounds", "look_at", "end_effector"])
def test_a_new_constraint_starts_next_to_the_character(studio, qtbot, kind):
    """Defaults were fixed numbers: a box at the origin, a look-at target at (0, -2, 1.6)."""
    studio.session.seek(100)  # the synthetic walk is ~2 m from the origin by now
    qtbot.waitUntil(lambda: studio.session.latest.frame == 100)
    pose = studio.session.latest.positions
    studio.constraint_panel.kinds.setCurrentText(kind)
    studio.constraint_panel.add_button.click()
    (c,) = studio.session.constraints
    if kind == "bounds":
        root = pose[sk.JOINT_INDEX["root"]]
        assert np.all(c.box_min < root) and np.all(root < c.box_max)
        assert np.all(c.box_max - c.box_min < 1.5)
    elif kind == "look_at":
        head = pose[sk.JOINT_INDEX[c.joint]]
        assert np.linalg.norm(c.target - head) == pytest.approx(LOOK_DISTANCE, abs=0.05)
        # in front of the face: the direction the hips face, give or take
        assert np.isclose(c.target[2], head[2])
    else:
        assert np.linalg.norm(c.position - pose[sk.JOINT_INDEX[c.joint]]) < 0.3


def test_a_pin_put_on_another_joint_in_its_editor_is_placed_on_that_joint(studio, qtbot):
    """Added on the ankle, then the wrist chosen in the editor: the pin goes where the
    wrist is, not left at the ankle's place, where it drags the wrist to the floor."""
    from PyQt6.QtWidgets import QComboBox

    studio.session.seek(100)
    qtbot.waitUntil(lambda: studio.session.latest.frame == 100)
    pose = studio.session.latest.positions.copy()
    panel = studio.constraint_panel
    panel.kinds.setCurrentText("pin")
    panel.add_button.click()
    (joint_box,) = [b for b in panel.editor.findChildren(QComboBox) if b.currentText() == "lankle"]
    joint_box.setCurrentText("lwrist")
    (c,) = studio.session.constraints
    assert c.joint == "lwrist"
    assert np.linalg.norm(c.position - pose[sk.JOINT_INDEX["lwrist"]]) < 0.05


def test_pins_added_from_the_panel_take_the_clicked_joint_or_a_free_one(studio, qtbot):
    """Add pressed twice with *pin* chosen puts the pins on two joints: the left ankle,
    then the right; after a click on the left elbow in the 3D view, the next one goes on
    the elbow, where the elbow is."""
    from PyQt6.QtCore import Qt
    from PyQt6.QtTest import QTest

    from tests.app.gui_helpers import pixel_of
    from tests.app.test_pose_selection import click

    s, view, panel = studio.session, studio.viewport, studio.constraint_panel
    s.pause()
    qtbot.waitUntil(lambda: not s.latest.playing, timeout=10000)
    panel.kinds.setCurrentText("pin")
    QTest.mouseClick(panel.add_button, Qt.MouseButton.LeftButton)
    QTest.mouseClick(panel.add_button, Qt.MouseButton.LeftButton)
    assert [c.joint for c in s.constraints] == ["lankle", "rankle"]
    view.show_snapshot(s.latest)
    elbow = s.latest.positions[sk.JOINT_INDEX["lelbow"]]
    click(view, *pixel_of(view, elbow))
    assert studio.motion_paths.selected == "lelbow"
    QTest.mouseClick(panel.add_button, Qt.MouseButton.LeftButton)
    pin = s.constraints[-1]
    assert pin.joint == "lelbow" and np.linalg.norm(pin.position - elbow) < 1e-6
