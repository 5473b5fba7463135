"""research/stability_check.py: the pelvis-flip measure and one real reconstruction."""

from __future__ import annotations

import sys

import numpy as np

from .script_loader import ROOT, load_script


def _script():
    return load_script("stability_check")


def _about(axis: int, deg: float) -> np.ndarray:
    q = np.zeros(4)
    q[0], q[1 + axis] = np.cos(np.radians(deg) / 2), np.sin(np.radians(deg) / 2)
    return q


def test_pelvis_angle_sees_a_flip_and_ignores_the_quaternion_sign():
    sc = _script()
    q = np.tile([1.0, 0.0, 0.0, 0.0], (3, 1))
    turned = np.stack([[1.0, 0.0, 0.0, 0.0], _about(2, 30.0), _about(0, 175.0)])
    turned[0] *= -1.0  # the same rotation
    angle = sc.pelvis_angle_deg(q, turned)
    np.testing.assert_allclose(angle, [0.0, 30.0, 175.0], atol=1e-6)
    assert angle[2] > sc.FLIP_DEG > angle[1]


def test_heading_ignores_lean_and_sees_a_turn_about_the_vertical():
    """A truth leaning 65 deg (forward or sideways) against an upright reconstruction facing
    the same way is 65 deg off in total but not turned; a pelvis turned 175 deg is."""
    from engine.kinematics import quaternion as Q

    sc = _script()
    turn = lambda deg: Q.from_axis_angle(np.array([0.0, 0.0, 1.0]), np.radians(deg))  # noqa: E731
    lean = lambda axis, deg: Q.from_axis_angle(np.eye(3)[axis], np.radians(deg))  # noqa: E731
    truth = np.stack(
        [
            Q.mul(turn(30.0), lean(0, 65.0)),
            Q.mul(turn(30.0), lean(1, 65.0)),
            turn(30.0),
            Q.mul(turn(30.0), lean(0, 65.0)),
        ]
    )
    rec = np.stack([turn(30.0), turn(30.0), turn(-145.0), Q.mul(turn(100.0), lean(0, 10.0))])
    np.testing.assert_allclose(sc.pelvis_angle_deg(truth, rec)[:3], [65.0, 65.0, 175.0], atol=1e-6)
    heading = sc.heading_angle_deg(truth, rec)
    np.testing.assert_allclose(heading, [0.0, 0.0, 175.0, 70.0], atol=1e-6)
    assert heading[2] > sc.FLIP_DEG > heading[3]


def test_run_once_on_the_bundled_clip_is_repeatable():
    from engine.motion.retarget import load_motion

    sc = _script()
    motion = load_motion(ROOT / "assets" / "clips" / "example.bvh", max_frames=12)
    a = sc.run_once(motion, "3-head-hands", "realtime", 0.0, 0)
    b = sc.run_once(motion, "3-head-hands", "realtime", 0.0, 0)
    assert a["finite"] and np.array_equal(a.pop("rec_pos"), b.pop("rec_pos")) and a == b
    assert 0.0 < a["pos_cm"] < a["worst_frame_cm"] + 1e-9 and 0.0 <= a["pelvis_max_deg"] < 180.0
    assert 0.0 <= a["heading_max_deg"] <= a["pelvis_max_deg"] + 1e-6


def test_settings_reach_the_method():
    """``--set`` values are applied: a different iteration count gives another reconstruction."""
    from engine.motion.retarget import load_motion

    sc = _script()
    motion = load_motion(ROOT / "assets" / "clips" / "example.bvh", max_frames=6)
    a = sc.run_once(motion, "3-head-hands", "realtime", 0.0, 0)
    b = sc.run_once(motion, "3-head-hands", "realtime", 0.0, 0, {"iterations": 2})
    assert not np.allclose(a["rec_pos"], b["rec_pos"])


def test_main_on_an_explicit_file_writes_the_tables(tmp_path, monkeypatch, capsys):
    sc = _script()
    md, js = tmp_path / "t.md", tmp_path / "t.json"
    monkeypatch.setattr(
        sys,
        "argv",
        [
            "stability_check.py",
            str(ROOT / "assets" / "clips" / "example.bvh"),
            "--modes",
            "realtime",
            "--max-frames",
            "6",
            "--seeds",
            "1",
            "--set",
            "iterations=2",
            "--markdown",
            str(md),
            "--json",
            str(js),
        ],
    )
    code = sc.main()
    out = capsys.readouterr().out
    assert "clips/example" in out and code in (0, 1)
    lines = md.read_text().splitlines()
    assert lines[0].startswith("| file | mode |") and "| clips/example | realtime |" in lines[2]
    import json

    run = json.loads(js.read_text())
    assert run["settings"] == {"iterations": 2} and run["runs"][0]["apart_cm"] >= 0.0
