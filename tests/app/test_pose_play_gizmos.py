"""While the pose window plays its keys, a constraint's gizmo is drawn on the played frame:
a pin's tether runs from the pin to where its joint is in that frame (here a frame where
the pin blends in). Tied to the pose being edited instead, it would show a pin that holds
its joint as stretched away from it. Off its frames and blends a pin draws nothing
(tests/app/test_gizmo_ranges.py)."""

from __future__ import annotations

import numpy as np
import pytest

from engine import skeleton as sk
from engine.kinematics.fk import fk_positions

pytestmark = pytest.mark.gui

J = sk.JOINT_INDEX


def test_a_pin_s_tether_follows_its_joint_on_the_played_frames(pose_window):
    w = pose_window
    p = w.mode.pose.positions.copy()
    w.drag_joint("lwrist", p[J["lwrist"]] + [0.15, 0.0, 0.35])
    w.add_key(0)
    w.go_to(20)
    w.drag_joint("lwrist", p[J["lwrist"]] + [0.35, 0.0, -0.05])
    w.add_key(20)
    edited = w.mode.pose.positions[J["lelbow"]].copy()
    w.session.add_constraint("pin", joint="lelbow", position=edited + [0.3, 0.0, 0.3], frames=(20, 20), blend_in=15)
    w.go_to(0)
    w.playback.toggle()
    try:
        w.playback.seek(10)
        motion = w.session.baked.motion
        played = fk_positions(motion.local_rot[10], motion.root_pos[10], motion.skeleton.offsets)[J["lelbow"]]
        assert np.linalg.norm(played - w.mode.pose.positions[J["lelbow"]]) > 0.02, "the elbow moves between the keys"
        (item,) = w.viewport.gizmos.items.values()
        assert np.allclose(item.tether.points[0], played, atol=1e-6)
    finally:
        w.playback.stop()
    (item,) = w.viewport.gizmos.items.values()
    assert np.allclose(item.tether.points[0], w.mode.pose.positions[J["lelbow"]], atol=1e-6), "back on the pose"
