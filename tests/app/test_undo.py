"""Undo and redo of scene edits through the window (Ctrl+Z / Ctrl+Shift+Z)."""

from __future__ import annotations

import numpy as np
import pytest
from PyQt6.QtCore import Qt
from PyQt6.QtWidgets import QApplication

pytestmark = pytest.mark.gui


def test_sensor_toggle_and_preset_are_undone_and_redone(studio):
    s, stack = studio.session, studio.undo.history
    stack.clear()
    joint = next(iter(s.sensors))
    studio.sensor_panel.rows[joint]["enabled"].setChecked(False)
    assert not s.sensors[joint].enabled and stack.count() == 1
    stack.undo()
    assert s.sensors[joint].enabled and studio.sensor_panel.rows[joint]["enabled"].isChecked()
    stack.redo()
    assert not s.sensors[joint].enabled
    before = (s.preset, tuple(s.sensors))
    studio.sensor_panel.preset.setCurrentText("3-head-hands")
    assert s.preset == "3-head-hands"
    stack.undo()
    assert (s.preset, tuple(s.sensors)) == before and not s.sensors[joint].enabled


def test_a_target_drag_is_one_step(studio, monkeypatch):
    monkeypatch.setattr("engine.authoring.history.MERGE_S", 60.0)  # moves slowed by a loaded machine still merge
    s, stack = studio.session, studio.undo.history
    stack.clear()
    joint = next(iter(s.sensors))
    base = s.tracked_position(joint, s.frame)
    for dx in np.linspace(0.01, 0.3, 12):  # one mouse move each
        studio.viewport.targetDragged.emit(joint, base + [dx, 0, 0])
    assert stack.count() == 1 and np.allclose(s.sensors[joint].offset, [0.3, 0, 0])
    stack.undo()
    assert np.allclose(s.sensors[joint].offset, 0)
    stack.redo()
    assert np.allclose(s.sensors[joint].offset, [0.3, 0, 0])


def test_constraint_add_edit_drag_and_remove_undo_in_order(studio, qtbot, monkeypatch):
    s, stack, panel = studio.session, studio.undo.history, studio.constraint_panel
    stack.clear()
    panel.kinds.setCurrentText("end_effector")
    panel.add_button.click()
    (c,) = s.constraints
    name, placed = c.name, c.position.copy()
    monkeypatch.setattr("engine.authoring.history.MERGE_S", 0.0)  # each edit below its own step
    panel.editor.inputs["weight"].setValue(4.0)
    studio.viewport.gizmoEdited.emit(name, {"position": placed + [0.2, 0, 0]})
    panel.remove_button.click()
    assert list(s.constraints) == [] and stack.count() == 4
    stack.undo()  # the removal
    assert [k.name for k in s.constraints] == [name] and np.allclose(s.constraints[0].position, placed + [0.2, 0, 0])
    stack.undo()  # the drag
    assert np.allclose(s.constraints[0].position, placed) and s.constraints[0].weight == 4.0
    assert np.allclose(panel.editor.inputs["position"].spins[0].value(), placed[0], atol=1e-3)
    stack.undo()  # the weight
    assert s.constraints[0].weight == 1.0
    stack.undo()  # the addition
    assert list(s.constraints) == []
    for _ in range(4):
        stack.redo()
    assert list(s.constraints) == []


def test_a_ctrl_drag_pin_is_undone_in_one_step_from_the_keyboard(studio, qtbot):
    from PyQt6.QtTest import QTest

    s, stack = studio.session, studio.undo.history
    stack.clear()
    for x in (0.40, 0.45, 0.50):
        studio.viewport.jointDragged.emit("lelbow", np.array([x, 0.0, 1.3]))
    (pin,) = s.constraints
    assert np.allclose(pin.position, [0.5, 0, 1.3]) and stack.count() == 1
    studio.windowHandle().requestActivate()
    qtbot.waitUntil(lambda: QApplication.activeWindow() is studio)
    QTest.keyClick(studio.viewport, Qt.Key.Key_Z, Qt.KeyboardModifier.ControlModifier)
    assert list(s.constraints) == []
    QTest.keyClick(
        studio.viewport, Qt.Key.Key_Z, Qt.KeyboardModifier.ControlModifier | Qt.KeyboardModifier.ShiftModifier
    )
    assert [c.name for c in s.constraints] == [pin.name] and np.allclose(s.constraints[0].position, [0.5, 0, 1.3])
    # the engine receives undone state like any other edit
    qtbot.waitUntil(lambda: any(n == pin.name for n, _ in studio.session.latest.gizmos), timeout=5000)


def test_a_new_clip_starts_a_new_history(studio, synthetic_motion):
    joint = next(iter(studio.session.sensors))
    studio.session.sensors.edit(joint, weight=2.0)
    assert studio.undo.history.count() >= 1
    studio.session.set_motion(synthetic_motion.slice(0, 30))
    assert studio.undo.history.count() == 0


def test_the_starting_preset_is_not_an_undo_step_and_later_edits_are(studio, qtbot):
    from app.main import open_initial

    studio.settings.setValue("last_preset", "3-head-hands")
    open_initial(studio, None, None)
    stack = studio.undo.history
    assert studio.session.preset == "3-head-hands" and stack.count() == 0
    studio.sensor_panel.preset.setCurrentText("6")
    studio.constraint_panel.kinds.setCurrentText("look_at")
    studio.constraint_panel.add_button.click()
    studio.sensor_panel.rows["upperneck"]["enabled"].setChecked(False)
    assert stack.texts() == [
        "Sensor preset 6",
        "Add look_at",
        "Turn off head tracker",  # the panel's name for the tracker, and what the step does
    ]


def test_optimizer_settings_edits_are_undone_and_redone(studio, qtbot):
    """A setting typed in the optimizer panel is one step (a spin box's steps merge); undo
    puts back the value it had, or leaves it unset again for the method's profile."""
    from PyQt6.QtTest import QTest

    s, stack, panel = studio.session, studio.undo.history, studio.optimizer_panel
    stack.clear()
    before = dict(s.settings)
    lr = panel.editors["lr"]
    lr.setFocus()
    for _ in range(3):
        QTest.keyClick(lr, Qt.Key.Key_Up)
    assert s.settings["lr"] != before["lr"] and stack.count() == 1 and stack.undo_text() == "Set lr"
    unset = next(n for n in panel.editors if n not in s.settings and hasattr(panel.editors[n], "stepBy"))
    qtbot.wait(700)  # beyond the merge window
    panel.editors[unset].stepBy(1)
    assert unset in s.settings and stack.count() == 2
    stack.undo()
    assert unset not in s.settings and s.settings["lr"] != before["lr"]
    stack.undo()
    assert dict(s.settings) == before and lr.value() == pytest.approx(before["lr"])
    stack.redo()
    stack.redo()
    assert unset in s.settings and s.settings["lr"] != before["lr"]
