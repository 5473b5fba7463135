"""Constraints in the pose window: added from its constraint panel, honoured by the solve, undone."""

from __future__ import annotations

import numpy as np
import pytest

from engine import skeleton as sk

pytestmark = pytest.mark.gui
LW, LSH = sk.JOINT_INDEX["lwrist"], sk.JOINT_INDEX["lshoulder"]


def _reach_down(drag, start: np.ndarray) -> None:
    """Drag the left wrist 30 cm forward and down to 25 cm above the floor, in 30 moves."""
    goal = np.array([start[0], start[1] - 0.3, 0.25])
    for i in range(30):
        drag("lwrist", start + (goal - start) * (i + 1) / 30)


def test_a_floor_added_in_the_pose_window_holds_the_shoulder_up(qtbot, monkeypatch):
    from PyQt6.QtWidgets import QMessageBox

    from app.pose_window import PoseWindow
    from engine.authoring.pose_mode import PoseMode
    from engine.authoring.session import AuthoringSession
    from engine.models import load_default_models
    from tests.app.test_pose_window import close_now

    vae = load_default_models().vae

    free = PoseMode(vae, 1.75)  # the same drag with no constraint: the body bends down to reach
    start, top = free.pose.positions[LW].copy(), float(free.pose.positions[LSH][2])

    def free_drag(joint, p):
        free.set_target(joint, p)
        free.solve()

    _reach_down(free_drag, start)
    free.settle()

    monkeypatch.setattr(QMessageBox, "question", lambda *a, **k: QMessageBox.StandardButton.Discard)
    w = PoseWindow(AuthoringSession(PoseMode(vae, 1.75)))
    w.show()
    try:
        panel = w.constraints.panel
        panel.kinds.setCurrentText("floor")
        panel.add_button.click()
        (name,) = [c.name for c in w.mode.constraints]
        panel.changed.emit(name, {"joints": ("lshoulder",), "floor_height": top - 0.03, "weight": 5.0})
        assert w.scene.constraints is w.mode.constraints and w.mode.constraints[0].joints == ("lshoulder",)
        assert panel.list.count() == 1  # the panel shows it
        _reach_down(w.drag_joint, start)
        w.settle().wait()
        held = float(w.mode.pose.positions[LSH][2])
        bent = float(free.pose.positions[LSH][2])
        assert held > bent + 0.3, (held, bent)  # measured 1.22 m against 0.53 m
        assert held > top - 0.2
        steps = w.undo.count()
        while w.undo.can_undo():
            w.undo.undo()
        assert w.mode.constraints == [] and panel.list.count() == 0
        for _ in range(steps):
            w.undo.redo()
        assert w.mode.constraints[0].joints == ("lshoulder",)
        assert float(w.mode.pose.positions[LSH][2]) == held
    finally:
        close_now(w)
