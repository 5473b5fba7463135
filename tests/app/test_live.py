"""Live trackers in the studio under Xvfb: File > Connect live source with the real
sender on 127.0.0.1, the status light, Record / Stop, Calibrate; a recording opened like
a clip."""

from __future__ import annotations

import threading

import numpy as np
import pytest
from PyQt6.QtWidgets import QFileDialog

from engine.tracker_io.recording import read_recording, write_recording
from engine.tracker_io.sender import plan_stream, scaled_motion, send_stream
from engine.tracker_io.trackers import TrackerSample
from widgets.live_panel import DEFAULT_MAPPING, LIGHT

pytestmark = pytest.mark.gui


def test_connect_record_and_calibrate_a_live_stream(studio, qtbot, synthetic_motion, tmp_path, monkeypatch):
    assert studio.live.connect("127.0.0.1", 0)
    # the next Connect dialog offers what was used (no mapping given: the default one)
    get = studio.settings.value
    assert (get("live_host"), get("live_mapping"), get("live_convention")) == ("127.0.0.1", DEFAULT_MAPPING, "unity")
    src = studio.session.source
    assert src.live and studio.session.motion is None
    subject = scaled_motion(synthetic_motion.slice(0, 90), 1.1)
    plan = plan_stream(subject, "6", tpose_s=1.5, hardware_offsets=True)
    rec = tmp_path / "live.jsonl"
    monkeypatch.setattr(QFileDialog, "getSaveFileName", lambda *a, **k: (str(rec), ""))
    studio.live.panel.record.click()  # Record
    studio.live.panel.countdown.setValue(0.0)
    studio.live.panel.window.setValue(1.0)
    studio.live.panel.calibrate.click()
    sender = threading.Thread(target=send_stream, args=(plan, "127.0.0.1", src.receiver.port, 60.0))
    sender.start()
    try:
        qtbot.waitUntil(
            lambda: (s := studio.session.latest) is not None and s.frame > 30 and bool(s.target_joints), timeout=15000
        )
        qtbot.waitUntil(lambda: LIGHT["ok"] in studio.live.panel.light.styleSheet(), timeout=5000)
        assert "packets/s" in studio.live.panel.figures.text()
        qtbot.waitUntil(lambda: src.skeleton_version == 1, timeout=15000)
    finally:
        sender.join()
    snap = studio.session.latest
    assert "latency_ms" in snap.timing and np.isnan(snap.ground_truth).all()
    true_h = subject.skeleton.height()
    assert abs(src.skeleton.height() - true_h) / true_h < 0.02
    qtbot.waitUntil(lambda: "calibrated (tpose" in studio.live.panel.calibration.text(), timeout=5000)
    qtbot.waitUntil(lambda: studio.timeline.slider.maximum() == len(plan) - 1, timeout=5000)
    studio.live.panel.record.click()  # Stop: the file appears
    assert len(read_recording(rec).samples) == 6 * len(plan)
    studio.live.panel.disconnect.click()
    assert not src.receiver.running and LIGHT["off"] in studio.live.panel.light.styleSheet()


def test_a_tracker_recording_opens_like_a_clip(studio, qtbot, synthetic_motion, tmp_path):
    plan = plan_stream(synthetic_motion.slice(0, 40), "6")
    samples = [TrackerSample(float(plan.times[i]), n, p, r) for i in range(len(plan)) for n, p, r in plan.frame(i)]
    path = tmp_path / "rec.jsonl"
    write_recording(path, samples, 60.0)
    studio.session.constraints.add("floor")  # an edit, discarded by opening the recording
    assert not studio.undo.is_clean()
    assert studio.live.open_recording(path)
    assert studio.undo.is_clean()  # a new history: opening something else asks nothing more
    studio.session.seek(20)
    snap = studio.session.latest
    qtbot.waitUntil(
        lambda: (s := studio.session.latest) is not None and s.frame == 20 and s.num_frames == 40, timeout=10000
    )
    snap = studio.session.latest
    assert np.isnan(snap.ground_truth).all() and len(snap.target_joints) == 6
    assert studio.timeline.slider.maximum() == 39 and "rec.jsonl" in studio.windowTitle()
    # the reconstruction follows the recorded trackers
    i = list(snap.target_joints).index("upperneck")
    assert np.linalg.norm(snap.positions[13] - snap.target_positions[i]) < 0.1


def test_connecting_clears_the_previous_character_from_the_view(studio, qtbot, synthetic_motion):
    """Connect before any tracker frame arrived: the clip's character (and its green ground
    truth) went on being drawn as if the stream were showing it; the view is empty and says
    it waits. Opening the clip again shows the clip."""
    from tests.widgets.test_viewport import orange_fraction

    view = studio.viewport
    qtbot.waitUntil(lambda: studio.drawing.draws > 0 and view.reconstruction.visible, timeout=10000)
    assert orange_fraction(view.plotter.screenshot(return_img=True)) > 0.002
    assert studio.live.connect("127.0.0.1", 0)
    qtbot.wait(300)  # display ticks: none may draw the clip's last snapshot again
    assert not view.reconstruction.visible and not view.ground_truth.visible
    assert view.sensors.joints == () and view.joints.positions is None
    assert "waiting for tracker frames" in view._caption
    assert orange_fraction(view.plotter.screenshot(return_img=True)) == 0.0
    studio.live.disconnect()
    qtbot.wait(100)
    assert not view.reconstruction.visible and "disconnected" in view._caption
    studio.session.set_motion(synthetic_motion)
    assert view.ground_truth.visible  # the clip's first frame at once
    qtbot.waitUntil(lambda: view.reconstruction.visible, timeout=10000)


def test_connecting_drops_the_clips_errors_and_motion_paths(studio, qtbot):
    """After Connect the Method errors plot holds no curve or legend of the clip, and the
    3D view no motion path of it: a stream of trackers has no ground truth and no path
    yet."""
    with qtbot.waitSignal(studio.snapshotDrawn, timeout=10000, check_params_cb=lambda f: f == 10):
        studio.session.seek(10)
    assert studio.method_errors.data  # the clip's error on the frame drawn
    studio.motion_paths.select("relbow")
    assert studio.motion_paths.layer.paths  # the clip's path of the elbow, drawn
    assert studio.live.connect("127.0.0.1", 0)
    qtbot.wait(300)
    assert not studio.method_errors.data and not studio.method_errors.legend.text()
    assert not studio.motion_paths.layer.paths
    studio.live.disconnect()
