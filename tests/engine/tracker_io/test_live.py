"""Live reconstruction over a real UDP socket on 127.0.0.1: the real sender against the
real receiver, solved by a real method (IK, fast enough for tests); the CLI commands
``send``, ``live`` and ``reconstruct --trackers`` end to end. Bounded: about a second of
stream per test."""

from __future__ import annotations

import json
import socket
import threading

import numpy as np
import pytest

from engine.cli.main import main
from engine.methods import get_method
from engine.motion.bvh import save_motion_bvh
from engine.motion.retarget import load_motion
from engine.tracker_io.live import LiveRun, reference_error, to_motion, tracker_error_cm
from engine.tracker_io.receiver import VMCReceiver
from engine.tracker_io.sender import plan_stream, send_stream


def _free_port() -> int:
    s = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    s.bind(("127.0.0.1", 0))
    port = s.getsockname()[1]
    s.close()
    return port


def test_live_run_solves_the_stream_like_simulated_sensors(synthetic_motion):
    motion = synthetic_motion.slice(0, 60)
    with VMCReceiver("127.0.0.1", 0) as rx:
        run = LiveRun(rx, get_method("ik"), motion.skeleton, 60.0)
        sender = threading.Thread(target=send_stream, args=(plan_stream(motion, "6"), "127.0.0.1", rx.port, 60.0))
        sender.start()
        out = run.run(duration_s=20.0, idle_timeout_s=0.5)
        sender.join()
    assert out.frames_received == 60 and out.frames_solved + out.frames_skipped == 60
    assert out.frames_solved >= 5 and len(out.figures.latency_ms) == out.frames_solved
    assert all(lat > 0 for lat in out.figures.latency_ms)
    err = reference_error(out.times, out.results, motion)
    assert err["frames_compared"] == out.frames_solved and err["pos_cm"] < 10.0
    rec = to_motion(out.times, out.results, motion.skeleton, 60.0)
    assert len(rec) == round((out.times[-1] - out.times[0]) * 60) + 1
    assert reference_error(out.times, out.results, None)["pos_cm"] is None
    assert out.tracker_error_cm() == pytest.approx(tracker_error_cm(out.results, out.sensors))


def test_a_live_run_that_keeps_no_frames_keeps_the_figures_only(synthetic_motion):
    """`live` without --out or --reference: an hour's stream must not hold every pose."""
    motion = synthetic_motion.slice(0, 30)
    with VMCReceiver("127.0.0.1", 0) as rx:
        run = LiveRun(rx, get_method("ik"), motion.skeleton, 60.0, keep_frames=False)
        sender = threading.Thread(target=send_stream, args=(plan_stream(motion, "6"), "127.0.0.1", rx.port, 60.0))
        sender.start()
        out = run.run(duration_s=20.0, idle_timeout_s=0.5)
        sender.join()
    assert out.results == [] and out.sensors == [] and out.times == []
    assert out.frames_solved >= 5 and out.frames_solved == len(out.figures.latency_ms) == len(out.figures.solve_ms)
    assert out.frames_solved + out.frames_skipped == 30
    assert 0.0 < out.tracker_error_cm() < 20.0


def _run_live(args: list[str]) -> tuple[threading.Thread, list]:
    code: list = []
    t = threading.Thread(target=lambda: code.append(main(["live", *args, "--no-progress"])))
    t.start()
    return t, code


def test_cli_send_live_and_reconstruct_with_drops_and_noise(synthetic_motion, tmp_path, capsys):
    clip = tmp_path / "clip.bvh"
    save_motion_bvh(clip, synthetic_motion)
    port = _free_port()
    stats, rec, out = tmp_path / "stats.json", tmp_path / "rec.jsonl", tmp_path / "live.bvh"
    live, code = _run_live(
        [
            "--listen",
            f"127.0.0.1:{port}",
            "--method",
            "ik",
            "--record",
            str(rec),
            "--out",
            str(out),
            "--json",
            str(stats),
            "--reference",
            str(clip),
            "--idle-stop",
            "0.7",
            "--duration",
            "30",
        ]
    )
    import time

    time.sleep(1.5)  # the receiver binds before the method warms up; packets before that are lost anyway
    assert (
        main(["send", str(clip), "--to", f"127.0.0.1:{port}", "--drop", "0.05", "--noise-pos", "0.02", "--no-progress"])
        == 0
    )
    live.join(timeout=60)
    assert not live.is_alive() and code == [0]
    s = json.loads(stats.read_text())
    for key in (
        "packets",
        "malformed_packets",
        "frames_received",
        "frames_solved",
        "frames_skipped",
        "solved_fraction",
        "latency_ms",
        "tracker_error_cm",
        "reference",
    ):
        assert key in s
    assert 100 <= s["packets"] < 120 and s["frames_solved"] > 0 and s["latency_ms"]["p95"] > 0
    assert s["reference"]["pos_cm"] is not None and np.isfinite(s["reference"]["pos_cm"])
    assert len(load_motion(out)) > 0
    capsys.readouterr()

    off, offj = tmp_path / "off.bvh", tmp_path / "off.json"
    assert (
        main(
            [
                "reconstruct",
                "--trackers",
                str(rec),
                "--out",
                str(off),
                "--method",
                "ik",
                "--reference",
                str(clip),
                "--json",
                str(offj),
                "--no-progress",
            ]
        )
        == 0
    )
    o = json.loads(offj.read_text())
    assert o["frames_solved"] == s["frames_received"]  # offline solves every received frame
    assert abs(o["reference"]["pos_cm"] - s["reference"]["pos_cm"]) < 3.0
    assert "error against the reference" in capsys.readouterr().out


@pytest.mark.parametrize("shape, fps", [("time-first", 60), ("time-last", 90)])
def test_cli_live_on_separate_messages_solves_the_sent_frames(shape, fps, synthetic_motion, tmp_path, capsys):
    clip = tmp_path / "clip.bvh"
    save_motion_bvh(clip, synthetic_motion)
    port = _free_port()
    stats, rec = tmp_path / "stats.json", tmp_path / "rec.jsonl"
    live, code = _run_live(
        [
            "--listen",
            f"127.0.0.1:{port}",
            "--method",
            "ik",
            "--record",
            str(rec),
            "--fps",
            str(fps),
            "--json",
            str(stats),
            "--reference",
            str(clip),
            "--idle-stop",
            "0.7",
            "--duration",
            "30",
        ]
    )
    import time

    time.sleep(1.5)
    assert (
        main(
            [
                "send",
                str(clip),
                "--to",
                f"127.0.0.1:{port}",
                "--packets",
                shape,
                "--chatter",
                "--fps",
                str(fps),
                "--max-frames",
                "60",
                "--no-progress",
            ]
        )
        == 0
    )
    live.join(timeout=60)
    assert code == [0]
    s = json.loads(stats.read_text())
    sent = int(np.floor(59 / 60 * fps)) + 1  # 60 clip frames resampled to fps
    assert s["packet_shape"] == shape and s["frames_received"] == sent and s["untimed"] == 0
    assert s["packets"] == sent * 15 and s["other_messages"] == sent * 8
    c = s["completeness"]
    assert c["frames"] == s["frames_solved"] and c["devices"] == 6 and c["complete"] >= c["frames"] - 2
    assert s["reference"]["pos_cm"] < 10.0
    out = capsys.readouterr().out
    assert "complete frames" in out and f"({shape})" in out
    offj = tmp_path / "off.json"
    assert (
        main(
            [
                "reconstruct",
                "--trackers",
                str(rec),
                "--out",
                str(tmp_path / "off.bvh"),
                "--method",
                "ik",
                "--json",
                str(offj),
                "--no-progress",
            ]
        )
        == 0
    )
    assert json.loads(offj.read_text())["frames_solved"] == sent  # the recording holds the same frames


def test_cli_calibrates_a_scaled_wearer(synthetic_motion, tmp_path, capsys):
    clip = tmp_path / "clip.bvh"
    save_motion_bvh(clip, synthetic_motion.slice(0, 30))
    port = _free_port()
    stats = tmp_path / "stats.json"
    live, code = _run_live(
        [
            "--listen",
            f"127.0.0.1:{port}",
            "--method",
            "ik",
            "--calibrate",
            "1",
            "--json",
            str(stats),
            "--idle-stop",
            "0.7",
            "--duration",
            "30",
        ]
    )
    import time

    time.sleep(1.5)
    assert (
        main(
            [
                "send",
                str(clip),
                "--to",
                f"127.0.0.1:{port}",
                "--tpose",
                "1.2",
                "--scale",
                "1.1",
                "--hardware-offsets",
                "--no-progress",
            ]
        )
        == 0
    )
    live.join(timeout=60)
    assert code == [0]
    s = json.loads(stats.read_text())
    true_h = synthetic_motion.skeleton.height() * 1.1
    assert s["calibration"]["pose"] == "tpose"
    assert abs(s["skeleton_height_m"] - true_h) / true_h < 0.02
    assert s["calibration_frames"] >= 60 and s["frames_solved"] > 0
    assert "calibrated (tpose" in capsys.readouterr().out


@pytest.mark.parametrize(
    "argv, message",
    [
        (["live", "--listen", "x"], "expected PORT or HOST:PORT"),
        (["live", "--duration", "-1"], "--duration must be a positive"),
        (["live", "--calibrate", "nan"], "--calibrate must be seconds"),
        (["live", "--out", "take.fbx"], "'.fbx' is not a motion format this program writes; known: .bvh"),
        (["send", "missing.bvh", "--to", "localhost"], "expected HOST:PORT"),
        (["send", "missing.bvh", "--to", "127.0.0.1:9", "--drop", "2"], "--drop must be in"),
        (["reconstruct", "--out", "x.bvh"], "give IN.bvh or --trackers"),
    ],
)
def test_cli_argument_errors(argv, message, capsys):
    assert main(argv) == 2
    assert message in capsys.readouterr().err
