"""Switching the reconstruction method in the Optimizer tab is an undo step: Ctrl+Z brings
the previous method back (the combo box and the engine follow) on the scene as it was,
Ctrl+Shift+Z switches again; ghosts likewise."""

from __future__ import annotations

import traceback

import numpy as np
import pytest
from PyQt6.QtCore import Qt
from PyQt6.QtWidgets import QApplication

pytestmark = pytest.mark.gui


def scene_of(s) -> tuple:
    return (
        s.preset,
        tuple((j, bool(x.enabled), tuple(np.round(x.offset, 9))) for j, x in s.sensors.items()),
        tuple(c.name for c in s.constraints),
        dict(s.settings),
    )


def test_a_method_switch_is_undone_and_redone_from_the_keyboard_with_the_scene_intact(studio, qtbot):
    from PyQt6.QtTest import QTest

    s, stack, panel = studio.session, studio.undo.history, studio.optimizer_panel
    studio.viewport.jointDragged.emit("lelbow", np.array([0.4, 0.0, 1.3]))  # a pin: a scene to keep
    panel.editors["lr"].stepBy(1)
    stack.clear()
    assert s.method == "ik" and panel.method.currentText() == "ik"
    scene = scene_of(s)
    panel.method.setCurrentText("dragposer")  # the user's choice in the combo box
    assert s.method == "dragposer" and stack.count() == 1 and stack.undo_text() == "Method dragposer"
    undo = next(a for a in studio.findChildren(type(studio.menuBar().actions()[0])) if a.text().startswith("&Undo"))
    assert undo.isEnabled() and undo.text() == "&Undo Method dragposer"
    studio.windowHandle().requestActivate()
    qtbot.waitUntil(lambda: QApplication.activeWindow() is studio)
    QTest.keyClick(studio.viewport, Qt.Key.Key_Z, Qt.KeyboardModifier.ControlModifier)
    assert s.method == "ik" and panel.method.currentText() == "ik" and scene_of(s) == scene
    qtbot.waitUntil(
        lambda: s.latest is not None and s.latest.method == "ik" and not s.latest.method_error, timeout=30000
    )
    QTest.keyClick(
        studio.viewport, Qt.Key.Key_Z, Qt.KeyboardModifier.ControlModifier | Qt.KeyboardModifier.ShiftModifier
    )
    assert s.method == "dragposer" and panel.method.currentText() == "dragposer" and scene_of(s) == scene
    qtbot.waitUntil(lambda: s.latest.method == "dragposer" and not s.latest.method_error, timeout=60000)
    # a ghost ticked is a step of its own, undone to none
    panel.ghost_boxes["ik"].click()
    assert s.ghosts == ("ik",) and stack.undo_text() == "Ghosts ik"
    stack.undo()
    assert s.ghosts == () and s.method == "dragposer" and not panel.ghost_boxes["ik"].isChecked()


def _refused_switch(studio, qtbot, monkeypatch, method: str) -> list[tuple]:
    """Choose ``method`` in the Optimizer tab's selector; the engine's refusal is awaited."""
    from PyQt6.QtWidgets import QMessageBox

    said: list[tuple] = []

    def critical(*a, **k):
        # a modal box opened inside the drawing tick would stop the drawing behind it
        inside = [f.name for f in traceback.extract_stack() if f.name == "tick" and f.filename.endswith("drawing.py")]
        said.append((*a[1:3], inside))

    monkeypatch.setattr(QMessageBox, "critical", critical)
    notices: list[tuple] = []
    begin = studio.busy.begin
    monkeypatch.setattr(studio.busy, "begin", lambda m, seq, what="": (notices.append((m, what)), begin(m, seq, what)))
    s, panel = studio.session, studio.optimizer_panel
    studio.undo.set_clean()
    assert s.method == "ik" and panel.method.currentText() == "ik"
    panel.method.setCurrentIndex(panel.method.findText(method))  # the user's choice in the combo box
    qtbot.waitUntil(lambda: bool(said), timeout=30000)
    assert said[0][2] == [], "the error box is opened after the drawing tick"
    assert notices == [(method, "Switching to")], "the refusal announces no switch back"
    assert not studio.busy.active and "Switching" not in studio.statusBar().currentMessage()
    return said


def _assert_nothing_switched(studio) -> None:
    s, stack, panel = studio.session, studio.undo.history, studio.optimizer_panel
    assert s.method == "ik" and panel.method.currentText() == "ik", "the selector shows the method running"
    assert stack.count() == 0 and not stack.can_undo() and studio.undo.is_clean()
    undo = next(a for a in studio.findChildren(type(studio.menuBar().actions()[0])) if a.text().startswith("&Undo"))
    assert not undo.isEnabled() and undo.text() == "&Undo"
    assert s.latest.method == "ik"


def test_a_method_that_cannot_run_from_the_trackers_is_refused_and_leaves_no_undo_step(studio, qtbot, monkeypatch):
    assert studio.session.preset == "6"  # RPM learnt head and hands only
    said = _refused_switch(studio, qtbot, monkeypatch, "rpm")
    assert said[0][0] == "Cannot switch method" and "'3-head-hands'" in said[0][1]
    _assert_nothing_switched(studio)


def test_a_method_whose_model_cannot_be_loaded_leaves_no_undo_step(studio, qtbot, monkeypatch):
    factory = studio.engine._factory

    def broken(name):
        if name == "dragposer":
            raise ValueError("assets/models/vae.pt: not a weights file")
        return factory(name)

    studio.engine._factory = broken  # looked up at each build
    said = _refused_switch(studio, qtbot, monkeypatch, "dragposer")
    assert "vae.pt" in said[0][1]
    _assert_nothing_switched(studio)


def test_a_refusal_replaced_by_a_newer_snapshot_before_the_tick_is_still_shown(studio, qtbot, monkeypatch):
    """The engine says a refusal in one snapshot; when it publishes faster than the window
    draws (the default solver process), a newer snapshot takes ``latest`` before the tick
    reads it. The refusal must still put the selector back and open the error box."""
    import dataclasses

    engine = studio.engine

    def newer_at_once(snap):  # the next snapshot, published before the window's tick
        if snap.method_error:
            engine.latest = dataclasses.replace(snap, method_error="", seq=snap.seq + 1)

    qtbot.waitUntil(lambda: studio.drawing._listened is engine)  # the window hears the engine
    engine.listeners.append(newer_at_once)
    said = _refused_switch(studio, qtbot, monkeypatch, "rpm")
    assert said[0][0] == "Cannot switch method" and "'3-head-hands'" in said[0][1]
    _assert_nothing_switched(studio)
