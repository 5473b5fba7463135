"""The pose window's key timeline and what goes with it, with real clicks, drags and
shortcuts on the real widgets (keys at frames 0 and 40, a wrist target on 40 only):
the row under the timeline keeps its layout whatever its label says; on an in-between
the Targets list says which key's targets do not act there; undo and redo of a key
added, moved or deleted show the frame the key is at."""

from __future__ import annotations

import numpy as np
import pytest
from PyQt6.QtCore import Qt
from PyQt6.QtWidgets import QApplication

from tests.app.gui_helpers import drag_on_strip, drag_wrist, scrub, shortcut

pytestmark = pytest.mark.gui
REDO = Qt.KeyboardModifier.ControlModifier | Qt.KeyboardModifier.ShiftModifier


def _row(w) -> list:
    """Where each widget right of the label is, and the 3D view."""
    k = w.keys
    widgets = (k.add, k.delete, k.move_to, k.move, k.length, k.fps, k.interpolation, k.preview, k.loop)
    return [x.geometry() for x in widgets] + [k.label.geometry(), w.viewport.geometry()]


@pytest.mark.parametrize("width", [1000, 1500])
def test_the_row_under_the_timeline_keeps_its_layout_whatever_the_label_says(keyed, qtbot, width):
    w = keyed
    w.resize(width, 700)
    qtbot.waitUntil(lambda: w.width() == width)
    QApplication.processEvents()
    label = w.keys.label
    scrub(w, 20)
    first = _row(w)
    seen = {label.text(): first}
    for gesture in (
        lambda: scrub(w, 40),  # on a key
        lambda: scrub(w, 50),  # after the last key
        lambda: scrub(w, 20),
        lambda: drag_wrist(w),  # an in-between edited
        lambda: scrub(w, 0),  # the edit dropped: one undo step
        lambda: drag_wrist(w),  # a key edited
        lambda: shortcut(w, Qt.Key.Key_Z),  # the key as it was
        lambda: scrub(w, 20),
    ):
        gesture()
        QApplication.processEvents()
        seen[label.text()] = _row(w)
    for text, row in seen.items():
        assert row == first, f"{text!r} moved the row at {width} px"
    assert w.width() == width, "the window did not widen"
    texts = list(seen)
    assert any(t.startswith("frame 20 · unkeyed edit") for t in texts), texts
    assert any(t.startswith("key 0 · unkeyed edit") for t in texts), texts
    assert any(t.endswith("(in-between)") for t in texts) and any(t.endswith("(key)") for t in texts), texts
    for text in texts:  # every text the label showed here is whole
        assert label.fontMetrics().horizontalAdvance(text) <= label.contentsRect().width(), text


def test_an_in_between_lists_the_targets_of_one_key_that_do_not_act_there(keyed):
    w = keyed
    t = w.targets
    assert list(t.rows) == ["lwrist"] and not t.key_only.isVisible()  # on key 40
    scrub(w, 20)
    assert w.frame == 20 and not w.mode.targets, "an in-between takes the targets both keys have"
    assert not t.rows and t.key_only.isVisible()
    assert "lwrist (key 40)" in t.key_only.text() and "not acting on this frame" in t.key_only.text().lower()
    scrub(w, 30)  # another in-between of the same keys
    assert t.key_only.isVisible() and "lwrist (key 40)" in t.key_only.text()
    drag_wrist(w)  # a target here: a row, not the note
    assert list(t.rows) == ["lwrist"] and not t.key_only.isVisible()
    shortcut(w, Qt.Key.Key_Z)
    assert not t.rows and t.key_only.isVisible()
    scrub(w, 50)  # after the last key, its targets act
    assert list(t.rows) == ["lwrist"] and not t.key_only.isVisible()


def _at_key(w, frame: int) -> None:
    assert w.frame == frame and w.keys.strip.current == frame
    assert w.keys.label.text().startswith(f"frame {frame} /") and w.keys.label.text().endswith("(key)")
    key = w.session.key_at(frame)
    np.testing.assert_array_equal(w.mode.pose.latent, key.latent)
    np.testing.assert_allclose(w.viewport.joints.positions, w.mode.pose.positions)  # drawn


def test_undo_and_redo_of_a_key_moved_by_its_box_show_the_key(keyed):
    w = keyed
    w.keys.move_to.setValue(50)
    w.keys.move.click()
    assert [k.frame for k in w.scene.keys] == [0, 50] and w.frame == 50
    scrub(w, 10)
    shortcut(w, Qt.Key.Key_Z)
    assert [k.frame for k in w.scene.keys] == [0, 40]
    _at_key(w, 40)
    scrub(w, 10)
    shortcut(w, Qt.Key.Key_Z, REDO)
    assert [k.frame for k in w.scene.keys] == [0, 50]
    _at_key(w, 50)


def test_undo_and_redo_of_a_key_dragged_from_another_frame_show_the_key(keyed):
    w = keyed
    scrub(w, 20)
    drag_on_strip(w, 40, 30)
    assert [k.frame for k in w.scene.keys] == [0, 30] and w.frame == 30
    scrub(w, 10)
    shortcut(w, Qt.Key.Key_Z)
    assert [k.frame for k in w.scene.keys] == [0, 40] and "move key" in w.actions_by_name["redo"].text()
    _at_key(w, 40)
    shortcut(w, Qt.Key.Key_Z, REDO)
    _at_key(w, 30)


def test_undo_and_redo_of_a_key_added_or_deleted_show_its_frame(keyed):
    w = keyed
    scrub(w, 20)
    drag_wrist(w)
    edited = w.mode.pose.latent.copy()
    shortcut(w, Qt.Key.Key_K, Qt.KeyboardModifier.NoModifier)
    assert [k.frame for k in w.scene.keys] == [0, 20, 40]
    scrub(w, 50)
    shortcut(w, Qt.Key.Key_Z)  # the key gone: frame 20 with its edit, said unkeyed again
    assert [k.frame for k in w.scene.keys] == [0, 40] and w.frame == 20 and w.keys.strip.current == 20
    np.testing.assert_array_equal(w.mode.pose.latent, edited)
    assert w.keys.label.text().startswith("frame 20 · unkeyed edit")
    shortcut(w, Qt.Key.Key_Z, REDO)
    _at_key(w, 20)
    w.keys.delete.click()  # the pose stays, kept by no key
    assert [k.frame for k in w.scene.keys] == [0, 40]
    assert w.keys.label.text().startswith("frame 20 · unkeyed edit")
    scrub(w, 50)
    shortcut(w, Qt.Key.Key_Z)  # the pose dropped by leaving, back
    assert w.frame == 20 and w.keys.label.text().startswith("frame 20 · unkeyed edit")
    shortcut(w, Qt.Key.Key_Z)
    assert [k.frame for k in w.scene.keys] == [0, 20, 40]
    _at_key(w, 20)
    scrub(w, 50)
    shortcut(w, Qt.Key.Key_Z, REDO)
    assert [k.frame for k in w.scene.keys] == [0, 40] and w.frame == 20 and w.keys.strip.current == 20


def test_the_move_box_starts_at_the_key_shown_so_move_key_untouched_moves_nothing(keyed):
    """On a key the box beside Move key reads that key's frame, and the user types where
    it goes: the box kept 0 wherever the key timeline was, and Move key pressed on key 40
    without typing put it on frame 0, over the key there."""
    w = keyed
    scrub(w, 10)
    scrub(w, 40)
    assert w.keys.move_to.value() == 40
    w.keys.move.click()
    assert [k.frame for k in w.scene.keys] == [0, 40]
