"""Ghosts solved ahead in a process of their own give the poses of a solve in this one."""

from __future__ import annotations

import numpy as np
import pytest

from engine.errors import UserError
from engine.studio.clips import sensor_presets
from engine.studio.export import reconstruct_clip
from engine.studio.ghost_solve import GhostSolves


def test_streamed_poses_are_the_offline_solve(synthetic_motion):
    motion = synthetic_motion.slice(0, 30)
    sensors = sensor_presets()["6"]
    solves = GhostSolves(motion, sensors, ("ik",))
    try:
        first = solves.positions(0)["ik"]  # available before the whole clip is solved
        assert first.shape == (22, 3)
        streamed = solves.all_positions()["ik"]
    finally:
        solves.close()
    offline = reconstruct_clip(motion, sensors, (), {}, "ik").positions()
    np.testing.assert_allclose(streamed, offline, atol=1e-5)  # float32 on the way
    np.testing.assert_allclose(first, offline[0], atol=1e-5)


def test_a_failing_method_is_named(synthetic_motion):
    solves = GhostSolves(synthetic_motion.slice(0, 5), sensor_presets()["6"], ("no-such-method",))
    try:
        with pytest.raises(UserError, match="no-such-method"):
            solves.positions(0)
    finally:
        solves.close()
