"""scripts/stability_check.py: the pelvis-flip measure and one real reconstruction."""

from __future__ import annotations

import importlib.util
import sys
from pathlib import Path

import numpy as np


ROOT = Path(__file__).resolve().parents[2]


def _script():
    spec = importlib.util.spec_from_file_location("stability_check", ROOT / "scripts" / "stability_check.py")
    mod = importlib.util.module_from_spec(spec)
    sys.modules["stability_check"] = mod
    spec.loader.exec_module(mod)
    return mod


def _about(axis: int, deg: float) -> np.ndarray:
    q = np.zeros(4)
    q[0], q[1 + axis] = np.cos(np.radians(deg) / 2), np.sin(np.radians(deg) / 2)
    return q


def test_pelvis_angle_sees_a_flip_and_ignores_the_quaternion_sign():
    sc = _script()
    q = np.tile([1.0, 0.0, 0.0, 0.0], (3, 1))
    turned = np.stack([[1.0, 0.0, 0.0, 0.0],
                       _about(2, 30.0), _about(0, 175.0)])  # fmt: skip
    turned[0] *= -1.0  # the same rotation
    angle = sc.pelvis_angle_deg(q, turned)
    np.testing.assert_allclose(angle, [0.0, 30.0, 175.0], atol=1e-6)
    assert angle[2] > sc.FLIP_DEG > angle[1]


def test_run_once_on_the_bundled_clip_is_repeatable():
    from engine.retarget import load_motion

    sc = _script()
    motion = load_motion(ROOT / "assets" / "clips" / "example.bvh", max_frames=12)
    a = sc.run_once(motion, "3-head-hands", "realtime", 0.0, 0)
    b = sc.run_once(motion, "3-head-hands", "realtime", 0.0, 0)
    assert a["finite"] and a == b
    assert 0.0 < a["pos_cm"] < a["worst_frame_cm"] + 1e-9 and 0.0 <= a["pelvis_max_deg"] < 180.0
