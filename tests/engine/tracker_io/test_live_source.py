"""The studio's live source on a real UDP socket (127.0.0.1): frames kept for the
timeline, recording started and stopped while streaming, calibration after a countdown."""

from __future__ import annotations

import time

import numpy as np

from engine.sensors import Sensor
from engine.tracker_io.live_source import LiveSource
from engine.tracker_io.recording import read_recording
from engine.tracker_io.sender import plan_stream, scaled_motion, send_stream


def _wait(cond, timeout=5.0):
    end = time.monotonic() + timeout
    while time.monotonic() < end and not cond():
        time.sleep(0.01)
    return cond()


def test_frames_recording_and_calibration(synthetic_motion, tmp_path):
    subject = scaled_motion(synthetic_motion.slice(0, 30), 1.1)
    plan = plan_stream(subject, "6", tpose_s=1.0, hardware_offsets=True)
    src = LiveSource("127.0.0.1", 0, history_s=1.0).start()
    try:
        assert src.num_frames == 0 and src.frame(0).readings == {}
        src.start_calibration(countdown_s=0.0, window_s=0.5)
        src.start_recording(tmp_path / "rec.jsonl")
        st = send_stream(plan, "127.0.0.1", src.receiver.port, fps=120.0)
        assert _wait(lambda: src.status().frames == st.sent)
        path = src.stop_recording()
        status = src.status()
    finally:
        src.close()
    assert src.num_frames == len(plan) and status.packets == len(plan)
    assert status.calibration_phase == "done" and "calibrated (tpose" in status.calibration
    assert src.skeleton_version == 1
    true_h = subject.skeleton.height()
    assert abs(src.skeleton.height() - true_h) / true_h < 0.02
    assert len(read_recording(path).samples) == 6 * len(plan)
    # history keeps one second at 60 fps: older indices clamp to the oldest kept frame
    assert src.frame(0).readings.keys() == src.frame(len(plan) - 60).readings.keys()
    assert np.isnan(src.ground_truth(0)).all() and src.arrival(len(plan) - 1) is not None


def test_studio_sensor_edits_apply(synthetic_motion):
    src = LiveSource("127.0.0.1", 0).start()
    try:
        send_stream(plan_stream(synthetic_motion.slice(0, 5), "6"), "127.0.0.1", src.receiver.port, fps=200.0)
        assert _wait(lambda: src.num_frames == 5)
        raw = src.frame(4).readings
        src.set_sensors((Sensor("upperneck", dof=3, offset=(0.0, 0.0, 0.1)), Sensor("root", enabled=False)))
        edited = src.frame(4).readings
    finally:
        src.close()
    assert set(edited) == {"upperneck"} and edited["upperneck"].dof == 3
    np.testing.assert_allclose(edited["upperneck"].position, raw["upperneck"].position + [0, 0, 0.1])
    np.testing.assert_allclose(edited["upperneck"].rotation, [1, 0, 0, 0])


def test_a_failed_calibration_says_why(synthetic_motion):
    src = LiveSource("127.0.0.1", 0).start()
    try:
        src.start_calibration(countdown_s=0.0, window_s=0.05)
        plan = plan_stream(synthetic_motion.slice(0, 20), "lwrist,rwrist")
        send_stream(plan, "127.0.0.1", src.receiver.port, fps=200.0)
        assert _wait(lambda: src.status().calibration_phase == "done")
    finally:
        src.close()
    assert "calibration failed" in src.status().calibration and src.skeleton_version == 0


def test_a_recording_opens_like_a_clip(synthetic_motion, tmp_path):
    from engine.tracker_io.recording import write_recording
    from engine.tracker_io.recording_source import RecordingSource
    from engine.tracker_io.trackers import TrackerSample

    plan = plan_stream(scaled_motion(synthetic_motion, 0.9), "6", tpose_s=1.0, hardware_offsets=True)
    samples = [TrackerSample(float(plan.times[i]), n, p, r) for i in range(len(plan)) for n, p, r in plan.frame(i)]
    write_recording(tmp_path / "r.jsonl", samples, 60.0)
    src = RecordingSource(tmp_path / "r.jsonl", calibrate_s=0.8)
    assert src.num_frames == len(plan) and src.fps == 60.0 and src.motion is None
    assert set(src.frame(70).readings) == {"root", "upperneck", "lwrist", "rwrist", "lankle", "rankle"}
    assert src.calibration.pose == "tpose"
    true_h = synthetic_motion.skeleton.height() * 0.9
    assert abs(src.skeleton.height() - true_h) / true_h < 0.02
    src.set_sensors((Sensor("lwrist"),))
    assert set(src.frame(70).readings) == {"lwrist"}


def test_a_recording_that_received_nothing_writes_no_file(tmp_path):
    """A header-only file cannot be opened again ("no valid sample"): none is written."""
    src = LiveSource("127.0.0.1", 0).start()
    try:
        src.start_recording(tmp_path / "empty.jsonl")
        assert src.recording
        assert src.stop_recording() is None and not src.recording
    finally:
        src.close()
    assert list(tmp_path.iterdir()) == []


def test_a_calibration_with_no_frames_fails_and_a_later_stream_does_not_finish_it(synthetic_motion):
    from engine.tracker_io import live_source

    src = LiveSource("127.0.0.1", 0).start()
    try:
        src.start_calibration(countdown_s=0.05, window_s=0.05)
        assert src.status().calibration_phase == "countdown"
        time.sleep(0.1 + live_source.CALIBRATION_STALL_S)
        status = src.status()
        assert status.calibration_phase == "done" and "no tracker frame arrived" in status.calibration
        plan = plan_stream(synthetic_motion.slice(0, 20), "6")
        st = send_stream(plan, "127.0.0.1", src.receiver.port, fps=120.0)
        assert _wait(lambda: src.status().frames == st.sent)
        assert src.skeleton_version == 0 and src.calibration is None  # not calibrated unasked
    finally:
        src.close()
