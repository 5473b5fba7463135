"""The VMC receiver on a real UDP socket (127.0.0.1 only), fed by the real sender.

Every test is bounded: a few hundred datagrams at most and waits of a few seconds.
"""

from __future__ import annotations

import socket
import time

import numpy as np
import pytest
from pythonosc.osc_message_builder import OscMessageBuilder

from engine.errors import UserError
from engine.tracker_io.receiver import VMCReceiver, parse_listen
from engine.tracker_io.recording import RecordingWriter, header, read_recording, replay
from engine.tracker_io.sender import plan_stream, send_stream
from engine.tracker_io.trackers import TrackerMapping
from engine.tracker_io.vmc import HMD, decode_packet, encode_frame


def _wait(cond, timeout=5.0):
    end = time.monotonic() + timeout
    while time.monotonic() < end:
        if cond():
            return True
        time.sleep(0.01)
    return cond()


@pytest.fixture
def receiver():
    rx = VMCReceiver("127.0.0.1", 0).start()
    yield rx
    rx.stop()


@pytest.fixture
def sock():
    s = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    yield s
    s.close()


def test_encode_decode_round_trip():
    p, q = np.array([0.1, -0.2, 1.5]), np.array([0.8660254, 0.0, 0.5, 0.0])
    pkt = decode_packet(encode_frame(2.5, [("head", p, q), ("puck", p + 1, q)]))
    assert pkt.time == pytest.approx(2.5) and [x.tracker for x in pkt.poses] == ["head", "puck"]
    np.testing.assert_allclose(pkt.poses[0].position, p, atol=1e-6)  # OSC floats are 32-bit
    np.testing.assert_allclose(pkt.poses[0].rotation, q, atol=1e-6)


def test_a_streamed_clip_arrives_as_the_same_readings(receiver, synthetic_motion, tmp_path):
    plan = plan_stream(synthetic_motion.slice(0, 60), "6")
    stats = send_stream(plan, "127.0.0.1", receiver.port, fps=600.0)
    assert stats.sent == 60
    assert _wait(lambda: receiver.snapshot_stats().frames == 60)
    f = receiver.wait_frame(0, timeout=1.0)
    assert f.index == 60 and f.t == pytest.approx(59 / 60, abs=1e-5)
    truth = synthetic_motion.positions()[59]
    from engine import skeleton as sk

    for joint, r in f.sensors.readings.items():
        assert r.connected and r.dof == 6
        np.testing.assert_allclose(r.position, truth[sk.JOINT_INDEX[joint]], atol=1e-5)
    s = receiver.snapshot_stats()
    assert (s.samples, s.malformed_packets, s.duplicates, s.late) == (360, 0, 0, 0)


def test_bad_packets_are_counted_never_fatal(receiver, sock, synthetic_motion):
    addr = ("127.0.0.1", receiver.port)
    good = encode_frame(1.0, [("head", np.array([0, 0, 1.6]), np.array([1.0, 0, 0, 0]))])
    sock.sendto(good, addr)
    sock.sendto(b"\x00garbage that is not OSC", addr)  # malformed datagram
    sock.sendto(b"#bundle\x00\x00\x00", addr)  # truncated bundle
    bad = OscMessageBuilder(HMD)
    bad.add_arg("head")
    bad.add_arg(1.0)  # too few arguments
    sock.sendto(bad.build().dgram, addr)
    nan = OscMessageBuilder(HMD)
    for v in ("head", float("nan"), 0.0, 0.0, 0.0, 0.0, 0.0, 1.0):
        nan.add_arg(v)
    sock.sendto(nan.build().dgram, addr)
    other = OscMessageBuilder("/VMC/Ext/Blend/Val")
    other.add_arg("A")
    other.add_arg(0.5)
    sock.sendto(other.build().dgram, addr)
    sock.sendto(good, addr)  # duplicate
    sock.sendto(encode_frame(0.5, [("head", np.array([0, 0, 9.0]), np.array([1.0, 0, 0, 0]))]), addr)  # late
    sock.sendto(encode_frame(1.1, [("puck7", np.zeros(3), np.array([1.0, 0, 0, 0]))]), addr)  # unmapped
    sock.sendto(encode_frame(1.2, [("head", np.array([0, 0, 1.7]), np.array([1.0, 0, 0, 0]))]), addr)
    assert _wait(lambda: receiver.snapshot_stats().packets == 10)
    s = receiver.snapshot_stats()
    assert s.malformed_packets == 2 and s.malformed_messages == 2 and s.other_messages == 1
    assert s.duplicates == 1 and s.late == 1 and s.unmapped == 1 and receiver.unmapped_names == ["puck7"]
    assert s.frames == 3  # t = 1.0, 1.1, 1.2
    f = receiver.wait_frame(0, timeout=1.0)
    assert f.t == pytest.approx(1.2) and f.sensors.readings["upperneck"].position[2] == pytest.approx(1.7)
    assert receiver._thread.is_alive()


def test_a_restarted_sender_starts_the_state_over(receiver, sock):
    addr = ("127.0.0.1", receiver.port)
    for t in (10.0, 10.1, 0.0, 0.1):
        sock.sendto(encode_frame(t, [("head", np.array([0, 0, 1.6]), np.array([1.0, 0, 0, 0]))]), addr)
    assert _wait(lambda: receiver.snapshot_stats().packets == 4)
    s = receiver.snapshot_stats()
    assert s.restarts == 1 and s.late == 0 and s.frames == 4


def test_drops_and_noise_are_survived_and_the_recording_replays(tmp_path, synthetic_motion):
    path = tmp_path / "rec.jsonl"
    writer = RecordingWriter(path, header(60.0, TrackerMapping(), "test"))
    with VMCReceiver("127.0.0.1", 0, recorder=writer) as rx:
        plan = plan_stream(synthetic_motion, "6", noise_pos_m=0.02, seed=3)
        st = send_stream(plan, "127.0.0.1", rx.port, fps=600.0, drop=0.05, seed=3)
        assert 0 < st.dropped < 20
        assert _wait(lambda: rx.snapshot_stats().frames == st.sent)
    writer.close()
    rec = read_recording(path)
    assert len(rec.samples) == 6 * st.sent
    tracking, times = replay(rec.samples, rec.mapping)
    assert len(tracking) == st.sent and tracking.connected.all()  # a 1-frame gap is not a loss
    assert np.all(np.diff(times) > 0)


def test_listen_address_parsing():
    assert parse_listen("39539") == ("0.0.0.0", 39539)
    assert parse_listen("127.0.0.1:9000") == ("127.0.0.1", 9000)
    with pytest.raises(UserError, match="expected PORT or HOST:PORT"):
        parse_listen("abc")
    with pytest.raises(UserError, match="cannot listen"):
        with VMCReceiver("127.0.0.1", 0) as rx:
            VMCReceiver("127.0.0.1", rx.port)


@pytest.mark.parametrize("fps", [60.0, 90.0])
@pytest.mark.parametrize("shape", ["time-first", "time-last", "no-time"])
def test_separate_messages_make_the_sent_frames_and_the_recording_replays_to_them(
    shape, fps, synthetic_motion, tmp_path
):
    """One message per datagram in real time, with /VMC/Ext/OK, root and bone chatter mixed in."""
    plan = plan_stream(synthetic_motion.slice(0, 24), "6", fps=fps)
    path = tmp_path / "rec.jsonl"
    writer = RecordingWriter(path, header(fps, TrackerMapping(), "test"))
    published = []
    with VMCReceiver("127.0.0.1", 0, recorder=writer, on_frame=published.append) as rx:
        st = send_stream(plan, "127.0.0.1", rx.port, fps=fps, shape=shape, chatter=True)
        assert st.packets == len(plan) * (2 + 2 * 6 + (shape != "no-time"))
        # every datagram read, not only every frame made: chatter sent after a frame's last
        # bone can still be in the socket when that frame is published
        _wait(
            lambda: (
                (s := rx.snapshot_stats()).frames >= len(plan)
                and s.packets >= st.packets
                and not rx._assembler.deadline()
            ),
            timeout=3.0,
        )
        s = rx.snapshot_stats()
    writer.close()
    assert s.packet_shape == shape and s.other_messages == len(plan) * 8 and s.unmapped == 0
    assert s.duplicates == 0 and s.late == 0 and s.untimed == 0
    # every published frame holds the devices of one sent frame (no-time: in the order sent)
    truth = plan.positions
    sent = [int(np.argmin(np.abs(plan.times - f.t))) if shape != "no-time" else k for k, f in enumerate(published)]
    assert len(published) == len(plan) and sent == list(range(len(plan)))
    if shape != "no-time":
        np.testing.assert_allclose([f.t for f in published], plan.times, atol=1e-6)
    for f, i in zip(published[2:], sent[2:]):  # from the third frame the expected devices are known
        assert f.fresh == f.devices == 6
        for k, name in enumerate(plan.names):
            joint = TrackerMapping().slot(name)
            np.testing.assert_allclose(f.sensors.readings[joint].position, truth[i, k], atol=1e-5)
    # the recording replays to the same frames: same times, same readings
    rec = read_recording(path)
    tracking, times = replay(rec.samples, rec.mapping)
    np.testing.assert_array_equal(times, np.round([f.t for f in published], 6))
    for fi, f in enumerate(published):
        for k, j in enumerate(tracking.joints):
            np.testing.assert_allclose(tracking.positions[fi, k], f.sensors.readings[j].position, atol=2e-6)


def test_completeness_shows_a_sender_that_leaves_a_device_out(receiver, sock):
    addr = ("127.0.0.1", receiver.port)
    pose = (np.array([0, 0, 1.6]), np.array([1.0, 0, 0, 0]))
    for i in range(6):
        names = ["head", "left_hand", "right_hand"] if i % 2 == 0 else ["head", "left_hand"]
        sock.sendto(encode_frame(i / 60.0, [(n, *pose) for n in names]), addr)
    assert _wait(lambda: receiver.snapshot_stats().frames == 6)
    f = receiver.wait_frame(0, timeout=1.0)
    assert (f.index, f.fresh, f.devices) == (6, 2, 3)


def test_send_drops_single_datagrams_of_separate_messages(sock, synthetic_motion):
    sock.bind(("127.0.0.1", 0))
    plan = plan_stream(synthetic_motion.slice(0, 40), "6")
    st = send_stream(
        plan, "127.0.0.1", sock.getsockname()[1], fps=1000.0, drop=0.1, seed=2, shape="time-last", realtime=False
    )
    assert st.packets + st.packets_dropped == 40 * 7 and 0 < st.packets_dropped < 60
    assert st.sent + st.dropped == 40 and st.dropped <= st.packets_dropped
    with pytest.raises(UserError, match="--packets must be one of"):
        send_stream(plan, "127.0.0.1", 9, fps=60.0, shape="bundles")
