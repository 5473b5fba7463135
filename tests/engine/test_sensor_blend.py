"""Blending a tracker out and in on disconnect / reconnect (DragPoser's smooth transitions)."""

from __future__ import annotations

import numpy as np

from engine.methods.sensor_blend import SensorBlend, smoothstep


def _run(seconds: float, stream):
    b, out = SensorBlend(), []
    for pos, connected, solved in stream:
        out.append(b.update(np.asarray(pos, float), connected, np.asarray(solved, float), seconds, 10.0))
    return out


def test_zero_seconds_passes_the_stream_through():
    stream = [([i, 0, 0], i < 3 or i > 5, [0, 0, 0]) for i in range(9)]
    out = _run(0.0, stream)
    for (pos, connected, _), t in zip(stream, out):
        assert t.active == connected and t.weight == float(connected)
        if connected:
            np.testing.assert_allclose(t.position, pos)


def test_a_lost_tracker_ends_at_once_even_with_a_blend_time():
    stream = [([1, 2, 3], True, [0, 0, 0])] * 3 + [([9, 9, 9], False, [0, 0, 0])] * 4
    out = _run(0.5, stream)
    assert [t.active for t in out] == [True] * 3 + [False] * 4
    assert all(t.weight == 0.0 and t.rotation_weight == 0.0 for t in out[3:])


def test_blend_in_starts_at_the_solved_joint_and_glides_onto_the_tracker():
    stream = [([0, 0, 0], True, [0, 0, 0]), ([0, 0, 0], False, [0, 0, 0])]
    stream += [([1.0 + 0.1 * i, 0, 0], True, [0.5, 0, 0]) for i in range(8)]
    out = _run(0.5, stream)
    back = out[2:]
    gaps = [np.linalg.norm(t.position - np.array([1.0 + 0.1 * i, 0, 0])) for i, t in enumerate(back)]
    assert 0.3 < gaps[0] < 0.5, "starts near the solved joint (0.5 m from the tracker)"
    assert all(a > b for a, b in zip(gaps[:4], gaps[1:5])) and gaps[4] < 1e-12
    assert back[0].rotation_weight < 0.2 and back[-1].rotation_weight == 1.0


def test_smoothstep_ends():
    assert smoothstep(-1) == 0.0 and smoothstep(0.5) == 0.5 and smoothstep(2) == 1.0
