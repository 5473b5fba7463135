"""Every metric against hand-computed cases."""

from __future__ import annotations

import numpy as np
import pytest

from engine import metrics as M
from engine import skeleton as sk
from engine.kinematics import quaternion as Q
from engine.motion import Motion


def _static(frames: int = 60) -> Motion:
    rot = np.zeros((frames, sk.NUM_JOINTS, 4))
    rot[..., 0] = 1
    return Motion(rot, np.tile([0.0, 0.0, 0.95], (frames, 1)))


def _copy(m: Motion) -> Motion:
    return Motion(m.local_rot.copy(), m.root_pos.copy(), m.skeleton, m.fps)


def test_identical_motion_scores_zero(synthetic_motion):
    r = M.evaluate_motion(synthetic_motion, _copy(synthetic_motion))
    for k in ("pos_cm", "pos_rootaligned_cm", "rot_deg", "vel_cms", "ee_cm"):
        assert r[k] == pytest.approx(0.0, abs=1e-9)
    assert r["jitter"] == pytest.approx(r["gt_jitter"]) and r["frames"] == 120


def test_constant_offset_is_world_space(synthetic_motion):
    rec = _copy(synthetic_motion)
    rec.root_pos += [0.01, 0.0, 0.0]  # 1 cm
    r = M.evaluate_motion(synthetic_motion, rec)
    assert r["pos_cm"] == pytest.approx(1.0) and r["ee_cm"] == pytest.approx(1.0)
    assert r["pos_rootaligned_cm"] == pytest.approx(0.0, abs=1e-9)
    assert r["vel_cms"] == pytest.approx(0.0, abs=1e-9) and r["rot_deg"] == pytest.approx(0.0)


def test_one_joint_rotated_90_degrees():
    gt = _static()
    rec = _copy(gt)
    # a leaf joint (the toe): its rotation moves no joint, so only Rot changes
    rec.local_rot[:, sk.JOINT_INDEX["ltoe"]] = Q.from_axis_angle(np.array([0.0, 0, 1]), np.pi / 2)
    r = M.evaluate_motion(gt, rec)
    assert r["rot_deg"] == pytest.approx(90.0 / 22)
    assert r["pos_cm"] == pytest.approx(0.0, abs=1e-12)


def test_end_effector_error_counts_only_head_hands_feet():
    gt = _static()
    rec = _copy(gt)
    # bend the left elbow: moves only the left wrist among the end effectors
    rec.local_rot[:, sk.JOINT_INDEX["lelbow"]] = Q.from_axis_angle(np.array([0.0, 0, 1]), np.pi / 2)
    g, p = gt.positions(), rec.positions()
    d = 100 * np.linalg.norm(p[0, sk.JOINT_INDEX["lwrist"]] - g[0, sk.JOINT_INDEX["lwrist"]])
    r = M.evaluate_motion(gt, rec)
    assert r["ee_cm"] == pytest.approx(d / 5)
    assert r["pos_cm"] == pytest.approx(d / 22)


def test_velocity_error_of_a_drift():
    gt = _static()
    rec = _copy(gt)
    rec.root_pos[:, 1] += 0.5 * np.arange(60) / 60.0  # 0.5 m/s along Y
    assert M.evaluate_motion(gt, rec)["vel_cms"] == pytest.approx(50.0)


def test_jitter_of_a_cubic_trajectory():
    gt = _static(120)
    rec = _copy(gt)
    t = np.arange(120) / 60.0
    rec.root_pos[:, 2] += 2.0 * t**3  # jerk 12 m/s^3 everywhere, exact for finite differences
    r = M.evaluate_motion(gt, rec)
    assert r["jitter"] == pytest.approx(12.0 / 100)  # 10^2 m/s^3
    assert r["gt_jitter"] == pytest.approx(0.0, abs=1e-9)


def test_jerk_curve_is_causal():
    pos = np.zeros((10, 2, 3))
    pos[5:, :, 0] = 0.01  # a 1 cm step at frame 5
    j = M.jerk_curve(pos, 60.0)
    assert np.isnan(j[:3]).all() and (j[3:5] == 0).all()
    assert j[5] == pytest.approx(0.01 * 60**3 / 100)  # d3 = +1 step at frame 5
    assert j[6] == pytest.approx(2 * 0.01 * 60**3 / 100)  # 1 - 3
    assert j[7] == pytest.approx(0.01 * 60**3 / 100)  # 1 - 3 + 3
    assert j[8] == 0


def test_peak_jerk_and_area_after_transitions():
    fps = 60.0
    jerk = np.zeros(400)
    jerk[3:] = 0.1
    jerk[70] = 5.0
    jerk[250:253] = [2.0, 4.0, 1.0]
    conn = np.ones((400, 2), dtype=bool)
    conn[65:240, 0] = False  # lost at 65 (T-S), back at 240 (S-T)
    conn[380:, 1] = False  # window past the end: skipped
    r = M.transition_jerk(jerk, conn, fps)
    assert r["transitions"] == 2 and r["transitions_ts"] == 1 and r["transitions_st"] == 1
    assert r["pj_ts"] == pytest.approx(5.0)
    assert r["auj_ts"] == pytest.approx(5.0 + 59 * 0.1)
    assert r["pj_st"] == pytest.approx(4.0)
    assert r["auj_st"] == pytest.approx(7.0 + 57 * 0.1)
    assert r["pj"] == pytest.approx(4.5)
    empty = M.transition_jerk(jerk, np.ones((400, 2), bool), fps)
    assert empty["transitions"] == 0 and np.isnan(empty["pj"])


def test_evaluate_adds_transition_metrics_when_given_states(synthetic_motion):
    conn = np.ones((120, 1), bool)
    conn[20:40] = False
    r = M.evaluate_motion(synthetic_motion, _copy(synthetic_motion), connected=conn)
    assert r["transitions"] == 2 and r["pj"] > 0 and r["auj"] > r["pj"]


def test_summarize_is_frame_weighted():
    files = {
        "a": {"frames": 100, "pos_cm": 1.0, "pj": 2.0, "transitions": 1},
        "b": {"frames": 300, "pos_cm": 3.0, "pj": float("nan"), "transitions": 0},
        "c": {"frames": 100, "pos_cm": 1.0, "pj": 5.0, "transitions": 3},
    }
    t = M.summarize(files)
    assert t["frames"] == 500 and t["transitions"] == 4
    assert t["pos_cm"] == pytest.approx((100 + 900 + 100) / 500)
    assert t["pj"] == pytest.approx((2.0 + 15.0) / 4)
    assert M.summarize({}) == {"frames": 0}


def test_length_mismatch_is_rejected(synthetic_motion):
    with pytest.raises(ValueError, match="frames"):
        M.evaluate_motion(synthetic_motion, synthetic_motion.slice(0, 50))
