"""A constraint added, edited or removed on a key is a change of the scene, not an edit
of the key's pose: the key timeline says no unkeyed edit, and the key shows the pose the
bake gives on its frame (real clicks on the key timeline and the Constraints dock)."""

from __future__ import annotations

import numpy as np
import pytest
from PyQt6.QtCore import Qt
from PyQt6.QtTest import QTest

from engine import skeleton as sk
from engine.authoring.bake import solve_key
from tests.app.gui_helpers import scrub

pytestmark = pytest.mark.gui
J = sk.JOINT_INDEX


def test_a_pin_added_on_a_key_is_no_unkeyed_edit(keyed):
    w = keyed
    scrub(w, 40)  # the key with the raised wrist
    assert w.keys.label.text().endswith("(key)")
    before = w.mode.pose.positions.copy()
    panel = w.constraints.panel
    panel.kinds.setCurrentText("pin")
    QTest.mouseClick(panel.add_button, Qt.MouseButton.LeftButton)
    (pin,) = w.mode.constraints
    assert pin.kind == "pin"
    label = w.keys.label.text()
    assert "unkeyed" not in label and label.endswith("(key)"), label
    moved = np.linalg.norm(w.mode.pose.positions - before, axis=1)
    assert moved.max() < 1e-6, f"{sk.JOINT_NAMES[int(moved.argmax())]} moved {moved.max():.4f} m"
    # what the bake gives on the key's frame, drawn too
    baked = solve_key(w.session.scene, w.session.vae, w.session.key_at(40))
    np.testing.assert_allclose(w.mode.pose.positions, baked.positions, atol=1e-6)
    np.testing.assert_allclose(w.viewport.joints.positions, w.mode.pose.positions)
    # leaving the key drops nothing: no undo step for it
    steps = w.undo.count()
    scrub(w, 0)
    assert w.undo.count() == steps
    w.undo.undo()  # the pin's add, undone on the key it was added on
    assert not w.mode.constraints


def test_a_pin_edited_on_a_key_poses_the_key_under_it(keyed):
    """A pin moved onto the keyed wrist's joint, edited in the dock, takes the wrist
    (pins win over targets, as in the bake) without calling the key edited."""
    w = keyed
    scrub(w, 40)
    panel = w.constraints.panel
    panel.kinds.setCurrentText("pin")
    QTest.mouseClick(panel.add_button, Qt.MouseButton.LeftButton)
    (pin,) = w.mode.constraints
    place = w.mode.pose.positions[J["lwrist"]] + [0.0, -0.1, 0.0]
    w.session.update_constraint(pin.name, {"joint": "lwrist", "position": place})
    label = w.keys.label.text()
    assert "unkeyed" not in label, label
    assert np.linalg.norm(w.mode.pose.positions[J["lwrist"]] - place) < 1e-3
    w.session.remove_constraint(pin.name)
    assert "unkeyed" not in w.keys.label.text()
