"""Constraint frame ranges: activity weights, validation, JSON round trips, scenes."""

from __future__ import annotations

import json

import pytest

from engine.constraints import REGISTRY, FloorConstraint, PinConstraint, from_dict
from engine.errors import UserError
from engine.scene import scene_from_dict


def test_without_a_range_a_constraint_acts_on_every_frame():
    c = FloorConstraint()
    assert [c.activity(f) for f in (0, 7, 10**6)] == [1.0, 1.0, 1.0]
    assert c.active_frames() is None
    assert "frames" not in c.to_dict() and "blend_in" not in c.to_dict()


def test_activity_is_one_inside_zero_outside_and_rises_monotonically_in_the_blends():
    c = PinConstraint(joint="lwrist", frames=(10, 20), blend_in=4, blend_out=2)
    w = [c.activity(f) for f in range(0, 30)]
    assert w[10:21] == [1.0] * 11
    assert w[:6] == [0.0] * 6 and w[23:] == [0.0] * 7
    rising, falling = w[5:11], w[20:24]
    assert all(a < b for a, b in zip(rising, rising[1:])), rising
    assert all(a > b for a, b in zip(falling, falling[1:])), falling
    assert 0.0 < w[6] < 0.5 < w[9] < 1.0 and 0.0 < w[22] < w[21] < 1.0
    assert c.active_frames() == (6, 22)


def test_a_range_without_blends_switches_at_its_ends():
    c = PinConstraint(joint="lwrist", frames=(3, 3))
    assert [c.activity(f) for f in range(2, 5)] == [0.0, 1.0, 0.0]


@pytest.mark.parametrize("kind", sorted(REGISTRY))
def test_every_kind_keeps_its_range_through_json(kind):
    c = REGISTRY[kind](name=f"ranged {kind}", frames=(5, 9), blend_in=2, blend_out=3)
    back = from_dict(json.loads(json.dumps(c.to_dict(), allow_nan=False)))
    assert back.frames == (5, 9) and (back.blend_in, back.blend_out) == (2, 3)
    assert back.to_dict() == c.to_dict()


@pytest.mark.parametrize(
    "extra, field",
    [
        ({"frames": [5]}, "frames"),
        ({"frames": [9, 5]}, "frames"),
        ({"frames": [-1, 5]}, "frames"),
        ({"frames": [0.5, 5]}, "frames"),
        ({"frames": "0-5"}, "frames"),
        ({"frames": [0, 5], "blend_in": -2}, "blend_in"),
        ({"blend_out": 1.5}, "blend_out"),
        ({"blend_out": True}, "blend_out"),
    ],
)
def test_bad_ranges_are_named(extra, field):
    with pytest.raises(UserError, match=field):
        from_dict({"kind": "floor", **extra})


def test_a_scene_carries_the_range_and_names_a_bad_one():
    doc = {
        "format": "dragposer-scene",
        "version": 1,
        "constraints": [{"kind": "floor", "name": "f", "frames": [2, 8], "blend_in": 1}],
    }
    (c,), _ = scene_from_dict(doc, "s.json")
    assert c.frames == (2, 8) and c.activity(1) > 0 and c.activity(0) == 0
    doc["constraints"][0]["frames"] = [8, 2]
    with pytest.raises(UserError, match=r"s.json: constraints\[0\].*frames"):
        scene_from_dict(doc, "s.json")


def test_dragposer_weighs_a_range_by_the_clip_frame_it_solves_not_by_its_solve_count():
    """The studio resets the method on a seek and solves the frame sought first: a pin
    limited to frames 10-20 acts when frame 15 is the first one solved (frame 0 of the
    count of solves, outside the range) and not on frame 3 after frame 2."""
    import numpy as np
    import torch

    from engine.methods.dragposer import DragPoserMethod
    from engine.motion.clip import Motion
    from engine.tracking import simulate
    from tests.engine.test_optimizer_standins import CountingPredictor, MLPDecoder

    f = 24
    t = np.arange(f) / 60.0
    clip = Motion(np.tile(np.array([1.0, 0.0, 0.0, 0.0]), (f, 22, 1)), np.stack([0.2 * t, -0.8 * t, 1.0 + 0 * t], -1))
    tracking = simulate(clip, "6")
    torch.manual_seed(0)
    m = DragPoserMethod(MLPDecoder(), CountingPredictor(), iterations=3, max_iterations=20)
    m.reset(clip.skeleton)
    m.set_constraints(
        [PinConstraint(name="held", joint="lelbow", position=np.array([0.2, -0.3, 1.2]), frames=(10, 20))]
    )
    assert "held" in m.step(tracking.frame(15)).losses[-1]  # the first solve after a reset, inside the range
    m.reset(clip.skeleton)
    first = [m.step(tracking.frame(i)).losses[-1] for i in (2, 3)]
    assert all("held" not in losses for losses in first)
