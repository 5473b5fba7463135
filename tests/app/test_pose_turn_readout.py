"""The angle of a ring turn is read out while the ring is dragged (real mouse events):
a user asked for a head turned 60 degrees has a number to stop at."""

from __future__ import annotations

import re

import numpy as np
import pytest

from engine import skeleton as sk
from engine.kinematics import quat_np as QN
from tests.app.gui_helpers import mouse_drag, pixel_of
from widgets.viewport.rings import AXES, circle

pytestmark = pytest.mark.gui
HEAD = sk.JOINT_INDEX["upperneck"]


def test_the_status_bar_reads_the_angle_of_a_ring_turn_while_it_is_dragged(pose_window):
    w = pose_window
    w.viewport.set_camera("top", w.hips())
    w.viewport.plotter.render()
    x, y = pixel_of(w.viewport, w.mode.pose.positions[HEAD])
    mouse_drag(w.viewport, (x, y), (x, y), steps=1)  # a click selects the head: its rings show
    rings = w.viewport.rings
    before = w.turns.world_rotation("upperneck")
    ring = circle(rings.center, AXES[2], rings.radius, 72)  # 5 degrees apart, counter-clockwise from above
    w.viewport.plotter.render()
    path = [pixel_of(w.viewport, ring[k]) for k in (0, 12)]  # 0 -> 60 degrees
    seen: list[str] = []
    mouse_drag(w.viewport, path[0], path[1], steps=12, on_move=lambda: seen.append(w.statusBar().currentMessage()))
    turn = QN.mul(w.mode.targets["upperneck"].rotation, QN.conjugate(before))
    turned = np.degrees(2 * np.arccos(min(1.0, abs(turn[0]))))
    message = w.statusBar().currentMessage()
    assert message.startswith("Turn upperneck about Z (blue ring): +") and message.endswith("(to its left)")
    shown = float(re.search(r"([+-]\d+) deg", message).group(1))
    assert shown == pytest.approx(turned, abs=1.0) and shown == pytest.approx(60.0, abs=3.0)
    assert len({m for m in seen if m.startswith("Turn upperneck")}) > 3, "the number follows the mouse"
