"""Calibration to the wearer: a skeleton scaled by +-10 % is recovered from a T-pose,
and the tracker-to-joint offsets of real mounting put the readings back on the joints."""

from __future__ import annotations

import numpy as np
import pytest

from engine import skeleton as sk
from engine.errors import UserError
from engine.kinematics import quaternion as Q
from engine.tracker_io.calibration import calibrate, scaled_skeleton
from engine.tracker_io.recording import replay
from engine.tracker_io.sender import TRACKER_NAMES, plan_stream, scaled_motion, with_tpose
from engine.tracker_io.trackers import TrackerMapping, TrackerSample


def _frames_of(plan, start=0, stop=None, calibration=None):
    samples = [
        TrackerSample(float(plan.times[i]), n, p, r) for i in range(len(plan))[start:stop] for n, p, r in plan.frame(i)
    ]
    tracking, _ = replay(samples, TrackerMapping(), calibration)
    return tracking


@pytest.mark.parametrize("factor", [0.9, 1.1])
def test_scaled_subject_recovered_from_a_tpose(synthetic_motion, factor):
    subject = scaled_motion(synthetic_motion, factor)
    plan = plan_stream(subject, "6", noise_pos_m=0.005, tpose_s=2.0, hardware_offsets=True, seed=1)
    window = _frames_of(plan, 0, 120)
    cal = calibrate([window.frame(i) for i in range(len(window))])
    assert cal.pose == "tpose"
    true_h = subject.skeleton.height()
    assert abs(cal.height_m - true_h) / true_h < 0.02
    assert cal.arm_scale == pytest.approx(factor, rel=0.03)
    assert set(cal.offsets) == set(TRACKER_NAMES)

    # after calibration the readings sit on the joints again (up to the common shift a
    # single pose cannot see: the trackers' mean horizontal offset)
    tracking = _frames_of(plan, 120, None, cal)
    truth = subject.positions()
    idx = [sk.JOINT_INDEX[j] for j in tracking.joints]
    err = np.linalg.norm(tracking.positions - truth[:, idx], axis=-1)
    raw = _frames_of(plan, 120)
    raw_err = np.linalg.norm(raw.positions - truth[:, idx], axis=-1)
    assert err.mean() < 0.05 and err.mean() < 0.6 * raw_err.mean()
    angle = Q.angle(tracking.rotations, subject.fk()[1][:, idx])
    assert np.degrees(angle).mean() < 2.0  # rotation offsets (10 to 180 degrees) removed


def test_standing_pose_scales_by_height_and_leaves_the_hands(synthetic_motion):
    still = synthetic_motion.slice(0, 1)
    still.local_rot[:] = Q.identity((sk.NUM_JOINTS,))
    # arms down: rotate the shoulders 80 degrees about the forward axis
    down = Q.from_axis_angle(np.array([0, 1.0, 0]), np.radians(80))
    still.local_rot[0, sk.JOINT_INDEX["lshoulder"]] = down
    still.local_rot[0, sk.JOINT_INDEX["rshoulder"]] = Q.conjugate(down)
    subject = scaled_motion(still, 1.08)
    subject.root_pos[:, 2] = 0.0
    subject = with_tpose(subject, 0.0)
    from engine.tracker_io.calibration import standing_root_height

    subject.root_pos[:, 2] = standing_root_height(subject.skeleton)
    plan = plan_stream(subject, "6")
    frames = _frames_of(plan)
    cal = calibrate([frames.frame(0)] * 30)
    assert cal.pose == "standing" and cal.arm_span_m is None
    assert cal.height_m == pytest.approx(subject.skeleton.height(), rel=0.02)
    assert "lwrist" not in cal.offsets and "upperneck" in cal.offsets


def test_calibration_errors():
    from engine.sensors import Sensor, SensorFrame

    with pytest.raises(UserError, match="no tracker was connected"):
        calibrate([])
    hand = SensorFrame(0, {"lwrist": Sensor("lwrist", np.array([0.5, 0, 1.4]), Q.identity())})
    with pytest.raises(UserError, match="needs a head or a hip tracker"):
        calibrate([hand])
    low = SensorFrame(0, {"upperneck": Sensor("upperneck", np.array([0, 0, 0.3]), Q.identity())})
    with pytest.raises(UserError, match="implausible size"):
        calibrate([low])
    head = SensorFrame(0, {"upperneck": Sensor("upperneck", np.array([0, 0, 1.6]), Q.identity())})
    with pytest.raises(UserError, match="T-pose needs both hand trackers"):
        calibrate([head], pose="tpose")


def test_scaled_skeleton_scales_arms_separately():
    s = scaled_skeleton(1.0, 1.2)
    lw = sk.JOINT_INDEX["lwrist"]
    assert np.allclose(s.offsets[lw], sk.REST_OFFSETS[lw] * 1.2)
    assert np.allclose(s.offsets[1], sk.REST_OFFSETS[1])
