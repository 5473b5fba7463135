"""A user constraint on a tracked wrist or ankle shows in the pose: the exact reach step
after the solve leaves that limb as solved instead of putting it back on its tracker."""

from __future__ import annotations

import numpy as np
import pytest

from engine import skeleton as sk


@pytest.mark.slow
def test_a_distance_between_tracked_wrists_changes_their_separation(synthetic_motion):
    from engine.constraints.distance import DistanceConstraint
    from engine.methods import get_method
    from engine.studio.clip_source import ClipSource
    from engine.studio.clips import sensor_presets
    from engine.studio.method_set import MethodSet

    sensors = sensor_presets()["6"]
    a, b = sk.JOINT_INDEX["lwrist"], sk.JOINT_INDEX["rwrist"]
    seps = {}
    for weight in (0.0, 30.0):
        src = ClipSource(synthetic_motion)
        src.set_sensors(sensors)
        methods = MethodSet(get_method, lambda msg: None)
        methods.select("dragposer", ())
        methods.set_sensors(sensors)
        methods.reset(src)
        if weight:
            methods.set_constraints((DistanceConstraint(name="hands", weight=weight, distance=0.3),))
        out = []
        for f in range(40, 70):
            pose = methods.step(methods.method, src.frame(f)).positions
            methods.between_frames()
            out.append(np.linalg.norm(pose[a] - pose[b]))
        seps[weight] = float(np.mean(out[-10:]))
    assert abs(seps[30.0] - 0.3) < 0.05, seps
    assert abs(seps[0.0] - 0.3) > 0.1, seps  # the trackers alone hold the hands elsewhere
