"""An edit of the pose on a frame that does not keep it, with real mouse events on the
view and the key timeline: the label says the edit is not keyed, leaving the frame says
that it was not kept, and Ctrl+Z brings it back exactly, on its frame."""

from __future__ import annotations

import numpy as np
import pytest
from PyQt6.QtCore import Qt

from engine import skeleton as sk
from tests.app.gui_helpers import drag_wrist, scrub, shortcut

pytestmark = pytest.mark.gui
LW = sk.JOINT_INDEX["lwrist"]


def test_an_edit_between_keys_is_said_unkeyed_and_comes_back_with_ctrl_z(keyed):
    w = keyed
    scrub(w, 20)
    assert w.frame == 20 and w.keys.label.text().endswith("(in-between)")
    drag_wrist(w)
    label = w.keys.label.text()
    assert label.startswith("frame 20") and "unkeyed edit" in label and "K to key" in label, label
    edited = w.session.state()
    steps = w.undo.count()
    scrub(w, 30)
    assert w.frame == 30
    assert "unkeyed" not in w.keys.label.text()
    assert "frame 20" in w.statusBar().currentMessage() and "Ctrl+Z" in w.statusBar().currentMessage()
    assert w.undo.count() == steps + 1 and "frame 20" in w.actions_by_name["undo"].text()
    shortcut(w, Qt.Key.Key_Z)
    assert w.frame == 20 and w.keys.strip.current == 20
    assert "Ctrl+Z" not in w.statusBar().currentMessage(), "the message of the step undone is gone"
    back = w.session.state()
    np.testing.assert_array_equal(back.pose.positions, edited.pose.positions)
    np.testing.assert_array_equal(back.pose.latent, edited.pose.latent)
    assert [t.joint for t in back.targets] == [t.joint for t in edited.targets]
    for a, b in zip(back.targets, edited.targets):
        np.testing.assert_array_equal(a.position, b.position)
    assert "unkeyed edit" in w.keys.label.text()
    np.testing.assert_allclose(w.viewport.joints.positions, edited.pose.positions)  # drawn too
    # keyed now, it stays: the in-between at 20 is the edit
    w.keys.add.click()
    assert "unkeyed" not in w.keys.label.text() and w.keys.label.text().endswith("(key)")
    scrub(w, 30)
    scrub(w, 20)
    np.testing.assert_allclose(w.mode.pose.positions[LW], edited.pose.positions[LW], atol=1e-6)


def test_an_edit_of_a_key_not_keyed_again_is_said_and_undone_exactly(keyed):
    w = keyed
    scrub(w, 0)
    assert w.keys.label.text().endswith("(key)")
    drag_wrist(w)
    assert w.keys.label.text().startswith("key 0 · unkeyed edit")
    edited = w.session.state()
    scrub(w, 0)  # a click on the frame shown keeps the edit
    assert w.frame == 0 and w.session.state().pose is edited.pose
    scrub(w, 10)
    assert w.frame == 10 and not np.array_equal(w.mode.pose.positions, edited.pose.positions)
    assert "frame 0" in w.statusBar().currentMessage()
    shortcut(w, Qt.Key.Key_Z)
    assert w.frame == 0 and w.session.state().pose is edited.pose
    assert w.keys.label.text().startswith("key 0 · unkeyed edit")
    shortcut(w, Qt.Key.Key_Z, Qt.KeyboardModifier.ControlModifier | Qt.KeyboardModifier.ShiftModifier)
    assert w.frame == 10 and "unkeyed" not in w.keys.label.text()
