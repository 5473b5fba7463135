"""Every metric against hand-computed cases."""

from __future__ import annotations

import numpy as np
import pytest

from engine import metrics as M
from engine import skeleton as sk
from engine.kinematics import quaternion as Q
from engine.motion.clip import Motion


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


def test_peak_jerk_curve_is_the_largest_joints_l1_jerk():
    pos = np.zeros((8, 3, 3))
    pos[5:, 1] = [0.01, -0.02, 0.0]  # joint 1 steps 1 cm in x and -2 cm in y at frame 5
    pos[5:, 2, 2] = 0.02  # joint 2 steps 2 cm in z: smaller L1 (2 cm against 3 cm)
    j = M.peak_jerk_curve(pos, 60.0)
    unit = 60**3 / 100
    assert np.isnan(j[:3]).all() and j[4] == 0
    np.testing.assert_allclose(j[5:8], np.array([0.03, 0.06, 0.03]) * unit)  # d3 = +1, -2, +1 steps


def _jerk_with_changes():
    jerk = np.zeros(400)
    jerk[3:] = 0.1
    jerk[70] = 5.0
    jerk[250:253] = [2.0, 4.0, 1.0]
    conn = np.ones((400, 2), dtype=bool)
    conn[65:240, 0] = False  # lost at 65 (T-S), back at 240 (S-T)
    conn[380:, 1] = False  # window past the end: skipped
    return jerk, conn


def test_peak_jerk_and_area_against_the_ground_truths_level():
    jerk, conn = _jerk_with_changes()
    r = M.transition_jerk(jerk, conn, 60.0, gt_jerk=0.1)
    assert r["transitions"] == 2 and r["transitions_ts"] == 1 and r["transitions_st"] == 1
    assert r["pj_ts"] == pytest.approx(5.0) and r["auj_ts"] == pytest.approx(4.9)
    assert r["pj_st"] == pytest.approx(4.0) and r["auj_st"] == pytest.approx(1.9 + 3.9 + 0.9)
    # both windows averaged frame by frame first: (5, 0.1) at offset 5, (0.1, 4) at 11
    assert r["pj"] == pytest.approx((5.0 + 0.1) / 2)
    assert r["auj"] == pytest.approx(4.9 / 2 + (1.9 + 3.9 + 0.9) / 2)
    assert len(r["jerk_window_sum"]) == 60 and r["jerk_window_sum"][5] == pytest.approx(5.1)
    # a motion exactly at the ground truth's level has no area; one below it has
    assert M.transition_jerk(np.full(400, 0.1), conn, 60.0, gt_jerk=0.1)["auj"] == pytest.approx(0.0)
    assert M.transition_jerk(np.zeros(400), conn, 60.0, gt_jerk=0.1)["auj"] == pytest.approx(6.0)
    empty = M.transition_jerk(jerk, np.ones((400, 2), bool), 60.0, gt_jerk=0.1)
    assert empty["transitions"] == 0 and np.isnan(empty["pj"]) and np.isnan(empty["auj"])


def test_raw_peak_jerk_and_area_keep_the_previous_sums():
    jerk, conn = _jerk_with_changes()
    r = M.transition_jerk_raw(jerk, conn, 60.0)
    assert r["pj_raw_ts"] == pytest.approx(5.0) and r["auj_raw_ts"] == pytest.approx(5.0 + 59 * 0.1)
    assert r["pj_raw_st"] == pytest.approx(4.0) and r["auj_raw_st"] == pytest.approx(7.0 + 57 * 0.1)
    assert r["pj_raw"] == pytest.approx(4.5)


def _gaps(frames: int) -> np.ndarray:
    conn = np.ones((frames, 1), bool)
    conn[20:40] = False
    return conn


def test_a_reconstruction_equal_to_a_constant_jerk_ground_truth_has_no_area():
    gt = _static(120)
    gt.root_pos[:, 2] += 2.0 * (np.arange(120) / 60.0) ** 3  # jerk 12 m/s^3 on every joint and frame
    r = M.evaluate_motion(gt, _copy(gt), connected=_gaps(120))
    assert r["gt_jerk"] == pytest.approx(0.12) and r["transitions"] == 2
    assert r["pj"] == pytest.approx(0.12) and r["auj"] == pytest.approx(0.0, abs=1e-9)
    assert r["auj_raw"] == pytest.approx(60 * 0.12)  # the plain sum counts the motion's own jerk
    assert (r["gt_pj"], r["gt_auj"]) == (r["pj"], r["auj"])


def test_a_step_after_a_transition_raises_peak_and_area(synthetic_motion):
    conn = _gaps(120)
    same = M.evaluate_motion(synthetic_motion, _copy(synthetic_motion), connected=conn)
    rec = _copy(synthetic_motion)
    rec.root_pos[85:, 0] += 0.02  # a 2 cm jump 45 frames after the reconnection at 40
    step = M.evaluate_motion(synthetic_motion, rec, connected=conn)
    assert step["pj"] > same["pj"] + 0.02 * 60**3 / 100 / 2
    assert step["auj"] > same["auj"] + 0.02 * 60**3 / 100
    assert step["pj_st"] > same["pj_st"] and step["pj_ts"] == pytest.approx(same["pj_ts"])
    assert step["gt_auj"] == same["gt_auj"] == pytest.approx(same["auj"])  # the floor is the ground truth's


def test_summarize_is_frame_weighted():
    files = {
        "a": {"frames": 100, "pos_cm": 1.0, "pj": 2.0, "transitions": 1},
        "b": {"frames": 300, "pos_cm": 3.0, "pj": float("nan"), "transitions": 0},
        "c": {"frames": 100, "pos_cm": 1.0, "pj": 5.0, "transitions": 3},
    }
    t = M.summarize(files)
    assert t["frames"] == 500 and t["transitions"] == 4
    assert t["pos_cm"] == pytest.approx((100 + 900 + 100) / 500)
    assert t["pj"] == pytest.approx((2.0 + 15.0) / 4)  # no window sums: a mean over transitions
    assert M.summarize({}) == {"frames": 0}


def test_length_mismatch_is_rejected(synthetic_motion):
    with pytest.raises(ValueError, match="frames"):
        M.evaluate_motion(synthetic_motion, synthetic_motion.slice(0, 50))


def test_summarize_pools_the_transition_windows_of_all_files():
    jerk, conn = _jerk_with_changes()
    conn[:, 1] = True  # no change at the seam of the two files below
    a = {"frames": 400, "gt_jerk": 0.1, **M.transition_jerk(jerk, conn, 60.0, gt_jerk=0.1)}
    b = {"frames": 400, "gt_jerk": 0.3, **M.transition_jerk(np.full(400, 0.2), conn, 60.0, gt_jerk=0.3)}
    t = M.summarize({"a": a, "b": b})
    assert t["gt_jerk"] == pytest.approx(0.2) and t["transitions"] == 4
    both = M.transition_jerk(np.r_[jerk, np.full(400, 0.2)], np.r_[conn, conn], 60.0, gt_jerk=0.2)
    for k in ("pj", "auj", "pj_ts", "auj_ts", "pj_st", "auj_st"):
        assert t[k] == pytest.approx(both[k]), k
    a["gt_jerk_window_sum"], b["gt_jerk_window_sum"] = a["jerk_window_sum"], b["jerk_window_sum"]
    t = M.summarize({"a": a, "b": b})
    assert (t["gt_pj"], t["gt_auj"]) == pytest.approx((both["pj"], both["auj"]))
