"""research/offline_divergence.py: re-solving a recorded frame reproduces it, so swaps mean something."""

from __future__ import annotations

import numpy as np

from .script_loader import ROOT, load_script


def _script():
    return load_script("offline_divergence")


def test_resolving_recorded_inputs_reproduces_the_frame_and_swaps_change_it():
    from engine.motion.retarget import load_motion

    sc = _script()
    motion = load_motion(ROOT / "assets" / "clips" / "example.bvh", max_frames=5)
    run = sc.record(motion, "3-head-hands", "realtime", 0.0, 0)
    other = sc.record(motion, "3-head-hands", "realtime", 1e-3, 1)
    assert len(run["inputs"]) == 5 and run["iterations"][1] == 10
    k = 3  # recorded at the end of the clip: the method's state has moved on since
    lat, _ = sc.resolve(run["method"], run["inputs"][k])
    np.testing.assert_allclose(lat, run["latent"][k], atol=1e-6)
    moved, _ = sc.resolve(run["method"], run["inputs"][k], targets=other["inputs"][k]["targets"])
    assert np.abs(moved - lat).max() > 1e-6
