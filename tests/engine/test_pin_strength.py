"""A pin holds its joint against six trackers with the shipped DragPoser (at weight 1 a
Ctrl-dragged joint stays 13-15 cm from its pin, hence the pin's default of 30)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from engine import skeleton as sk

REPO = Path(__file__).resolve().parents[2]


def test_a_pinned_elbow_stays_near_its_pin_with_six_trackers():
    if not (REPO / "assets" / "models" / "vae.pt").is_file():
        pytest.skip("shipped model not found in assets/models")
    from engine.constraints import PinConstraint
    from engine.methods import get_method
    from engine.motion.retarget import load_motion
    from engine.tracking import simulate

    # the pin pulls the elbow in over the first few frames (by 7.9, 6.8, 5.9, 4.3, 2.4,
    # 1.6, 1.5, 1.3 cm with one release's models) and then holds it; what matters is the hold
    clip = load_motion(REPO / "assets" / "clips" / "example.bvh").slice(200, 208)
    j = sk.JOINT_INDEX["lelbow"]
    target = clip.positions()[0, j] + [0.10, -0.10, 0.05]  # a Ctrl-drag of 15 cm
    method = get_method("dragposer")
    method.reset(clip.skeleton, clip.fps)
    method.add_constraint(PinConstraint(name="pin lelbow", joint="lelbow", position=target))
    tracks = simulate(clip, "6")
    for f in range(len(clip)):
        res = method.step(tracks.frame(f))
    assert np.linalg.norm(res.positions[j] - target) < 0.025
