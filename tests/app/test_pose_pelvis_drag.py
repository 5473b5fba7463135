"""Shift + drag on the hips in the pose window moves the pelvis alone (issue 50, defect 4):
real mouse events with Shift on the VTK view, the feet planted flat, the upper body kept."""

from __future__ import annotations

import numpy as np
import pytest

from engine import skeleton as sk
from tests.app.gui_helpers import mouse_drag, pixel_of

pytestmark = pytest.mark.gui

J = sk.JOINT_INDEX
FEET = [J[j] for j in ("lankle", "ltoe", "rankle", "rtoe")]
UPPER = [J[j] for j in ("lowerback", "chest", "upperneck", "lshoulder", "lwrist", "rshoulder", "rwrist")]


def test_shift_dragging_the_hips_down_squats_on_flat_feet(pose_window):
    w = pose_window
    w.viewport.set_camera("front", w.hips())
    w.viewport.plotter.render()
    before = w.mode.pose
    hips = before.positions[0]
    x, y = pixel_of(w.viewport, hips)
    _, y_low = pixel_of(w.viewport, hips - [0.0, 0.0, 0.30])
    messages = []
    w.viewport.jointDragged.connect(lambda j, p: messages.append(w.statusBar().currentMessage()))
    # pressed a little beside the hips, where the hip joints are nearer: Shift still takes the pelvis
    mouse_drag(w.viewport, (x + 9, y - 6), (x + 9, y_low - 6), steps=8, shift=True)
    after = w.mode.pose
    assert after.root_pos[2] == pytest.approx(hips[2] - 0.30, abs=0.02)
    assert np.linalg.norm(after.root_pos[:2] - hips[:2]) < 0.01  # straight down: not pushed back
    assert np.abs(after.positions[FEET] - before.positions[FEET]).max() < 1e-3  # flat where they stood
    rel_before = before.positions[UPPER] - before.positions[0]
    assert np.allclose(after.positions[UPPER] - after.positions[0], rel_before, atol=1e-6)
    assert w.mode.targets["root"].pelvis_only
    assert messages and all(m == "Pelvis only: feet planted" for m in messages)
    assert w.undo.undo_text() == "move pelvis" and w.undo.count() == 1
    w.undo.undo()
    assert np.array_equal(w.mode.pose.positions, before.positions) and w.mode.targets == {}


def test_the_help_lists_the_pelvis_drag(pose_window):
    from app.menu_parts import show_help

    rows = show_help(pose_window).rows()
    assert ("Shift + drag the hips", "Move only the pelvis, the feet planted flat (a squat)") in rows
