"""A short DragPoser run with the shipped models, shared by the latent-debugging tests."""

from __future__ import annotations

from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[3]
CLIP = REPO / "assets" / "clips" / "example.bvh"


@pytest.fixture(scope="package")
def dragposer_run():
    """DragPoser (shipped models, preset 6, realtime) stepped over the bundled clip's first
    6 frames; returns the method (its ``last_solve`` is frame 5's) and the results."""
    from engine.methods import driver, get_method
    from engine.motion.retarget import load_motion
    from engine.tracking import simulate

    motion = load_motion(CLIP).slice(0, 6)
    tracking = simulate(motion, "6")
    method = get_method("dragposer")
    driver.reset(method, motion.skeleton, motion.fps)
    results = [driver.step(method, tracking.frame(i)) for i in range(len(motion))]
    return method, results
