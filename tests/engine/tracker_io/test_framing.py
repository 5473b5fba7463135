"""Frames from the structure of a VMC stream (engine.tracker_io.framing), driven with
encoded datagrams and chosen wire times: no socket, no clock, every case exact."""

from __future__ import annotations

import numpy as np
import pytest

from engine.tracker_io.framing import FRAME_GAP_S, FrameAssembler
from engine.tracker_io.vmc import decode_packet, encode_packets

NAMES = ("head", "left_hand", "right_hand", "hips", "left_foot", "right_foot")
IDENTITY = np.array([1.0, 0.0, 0.0, 0.0])
T0 = 100.0  # wire time of the first frame
SPACING = 30e-6  # between the datagrams of one frame


def _stream(shape: str, fps: float, frames: int, chatter: bool = True, drop=lambda i, j: False):
    """(wire time, packet) of ``frames`` frames; device k of frame i is at x = i, y = k."""
    out = []
    for i in range(frames):
        poses = [(n, np.array([float(i), float(k), 1.0]), IDENTITY) for k, n in enumerate(NAMES)]
        for j, d in enumerate(encode_packets(i / fps, poses, "unity", shape, chatter)):
            if not drop(i, j):
                out.append((T0 + i / fps + j * SPACING, decode_packet(d)))
    return out


def _assemble(stream, asm: FrameAssembler | None = None):
    """Feed the stream, running the silence rules when they are due, as the receiver does.
    Returns the assembler and the closed frames as {t: {device: sent frame index}}, in order,
    with the fresh devices of each frame when it first closed."""
    asm = asm or FrameAssembler(clock_origin=T0)
    pieces = []
    for wire, packet in stream:
        due = asm.deadline()
        if due is not None and due < wire:
            pieces += asm.expire(due)
        pieces += asm.feed(packet, wire + 0.001, wire)
    pieces += asm.expire(stream[-1][0] + 1.0)
    frames: dict[float, dict[str, int]] = {}
    fresh_at_close: dict[float, int] = {}
    for p in pieces:
        got = frames.setdefault(p.t, {})
        for pose in p.poses:
            got[pose.tracker] = int(round(pose.position[0]))
        if p.close and p.t not in fresh_at_close:
            fresh_at_close[p.t] = len(got)
    return asm, frames, fresh_at_close


@pytest.mark.parametrize("fps", [60.0, 90.0])
@pytest.mark.parametrize("shape", ["bundle", "time-first", "time-last"])
def test_each_timed_shape_gives_every_frame_its_own_time_and_devices(shape, fps):
    asm, frames, fresh = _assemble(_stream(shape, fps, 20))
    assert asm.shape == shape and asm.untimed == 0
    assert list(frames) == pytest.approx([i / fps for i in range(20)])
    for i, got in enumerate(frames.values()):
        assert got == {n: i for n in NAMES}  # all six, all of the frame they were sent with
    # complete when first published: bundles at once, time first as soon as the six are in
    # (from the third frame; before, the expected devices are not known), time last at its time
    assert all(v == 6 for t, v in fresh.items() if t >= 2 / fps)


@pytest.mark.parametrize("fps", [60.0, 90.0])
def test_a_sender_without_time_gets_a_frame_per_burst(fps):
    asm, frames, fresh = _assemble(_stream("no-time", fps, 20))
    assert asm.shape == "no-time" and asm.untimed == 0
    times = np.array(list(frames))
    np.testing.assert_allclose(
        times, np.arange(20) / fps + 2 * SPACING, atol=1e-9
    )  # first device's wire time (after OK, root)
    for i, got in enumerate(frames.values()):
        assert got == {n: i for n in NAMES}
    assert all(v == 6 for v in list(fresh.values())[2:])


def test_time_first_closes_as_soon_as_the_expected_devices_are_in():
    fps = 60.0
    asm = FrameAssembler(clock_origin=T0)
    stream = _stream("time-first", fps, 4, chatter=False)
    closes = []
    for wire, packet in stream:
        closes += [(p.t, wire) for p in asm.feed(packet, wire, wire) if p.close]
    # frame 2 (from the third on the devices are expected) closes on its sixth device's datagram
    t2 = [w for t, w in closes if t == pytest.approx(2 / fps)]
    assert t2[0] == pytest.approx(T0 + 2 / fps + 6 * SPACING)


def test_time_last_closes_on_its_time():
    asm = FrameAssembler(clock_origin=T0)
    stream = _stream("time-last", 90.0, 6, chatter=False)
    arrivals = {}
    for wire, packet in stream:
        for p in asm.feed(packet, wire, wire):
            if p.close:
                arrivals.setdefault(round(p.t * 90.0), wire)  # when the close came out
    # after three votes the order is known and each time closes its frame when it arrives
    assert arrivals[5] == pytest.approx(T0 + 5 / 90.0 + 6 * SPACING)
    assert asm.order == "last"


@pytest.mark.parametrize("shape", ["time-first", "time-last", "no-time"])
def test_a_receiver_started_mid_frame_loses_at_most_the_first_frames(shape):
    fps = 60.0
    stream = _stream(shape, fps, 20)[5:]  # the first datagrams of the stream were missed
    asm, frames, _ = _assemble(stream)
    assert asm.shape == shape
    good = [got for got in frames.values() if len(set(got.values())) == 1 and len(got) == 6]
    assert len(frames) <= 20 and len(good) >= 18
    late = list(frames.values())[-17:]
    assert [set(g.values()) for g in late] == [{i} for i in range(3, 20)]


def test_a_lost_time_drops_its_devices_and_is_counted():
    def drop(i, j):  # frame 5's time: its own datagram, first in time-first, last in time-last
        return i == 5 and j == (0 if shape == "time-first" else 6)

    for shape in ("time-first", "time-last"):
        asm, frames, _ = _assemble(_stream(shape, 60.0, 10, chatter=False, drop=drop))
        assert pytest.approx(5 / 60.0) not in list(frames)
        assert len(frames) == 9
        for t, got in frames.items():
            assert set(got.values()) == {round(t * 60.0)}, shape  # nothing lands in another frame
        assert asm.untimed == 6


def test_a_lost_device_leaves_its_frame_incomplete_and_the_next_complete():
    drop = lambda i, j: i == 6 and j == 3  # noqa: E731  (frame 6's third device, time first)
    asm, frames, fresh = _assemble(_stream("time-first", 60.0, 10, chatter=False, drop=drop))
    assert len(frames) == 10 and fresh[list(frames)[6]] == 5
    assert [fresh[t] for t in list(frames)[7:]] == [6, 6, 6]


def test_a_device_that_stops_is_no_longer_waited_for():
    drop = lambda i, j: i >= 4 and j == 6  # noqa: E731  (the last device goes quiet from frame 4)
    asm = FrameAssembler(clock_origin=T0)
    closed_with = {}
    for wire, packet in _stream("time-first", 60.0, 10, chatter=False, drop=drop):
        for p in asm.feed(packet, wire, wire):
            if p.close:
                closed_with.setdefault(round(p.t * 60), wire)
    # frames 4 and 5 wait for it (closed by the next time), from frame 6 on they close at once
    assert closed_with[4] == pytest.approx(T0 + 5 / 60.0)
    assert closed_with[7] == pytest.approx(T0 + 7 / 60.0 + 5 * SPACING)


def test_the_order_is_set_by_votes_and_a_stray_stamp_does_not_turn_it():
    fps = 60.0
    stream = _stream("time-first", fps, 30, chatter=False)
    k = next(n for n, (w, p) in enumerate(stream) if p.time == pytest.approx(15 / fps))
    wire, packet = stream[k]
    stream[k] = (stream[k - 1][0] + 1e-6, packet)  # frame 15's time stamped right after frame 14
    asm, frames, _ = _assemble(stream)
    assert asm.order == "first" and len(frames) == 30
    assert all(set(g.values()) == {round(t * fps)} for t, g in frames.items())


def test_silence_of_a_sender_without_time_is_half_its_period():
    asm, _, _ = _assemble(_stream("no-time", 60.0, 20))
    assert asm.silence() == pytest.approx(0.5 / 60.0, rel=1e-3)
    assert FrameAssembler().silence() == FRAME_GAP_S  # before the period is known
    # a sender that stalls in the middle of a frame for longer splits it; a time keeps it whole
    stream = _stream("no-time", 60.0, 12, chatter=False)
    stream = [(w + (0.012 if w >= T0 + 10 / 60.0 + 3 * SPACING else 0.0), p) for w, p in stream]
    _, frames, _ = _assemble(stream)
    assert len(frames) == 13 and [len(g) for g in frames.values()][10:12] == [3, 3]


def test_bundles_with_devices_waiting_and_split_bundles():
    asm = FrameAssembler(clock_origin=T0)
    head, hand = NAMES[0], NAMES[1]
    p = [(head, np.zeros(3), IDENTITY), (hand, np.ones(3), IDENTITY)]
    split = encode_packets(1.0, p[:1], shape="bundle") + encode_packets(1.0, p[1:], shape="bundle")
    pieces = [pc for k, d in enumerate(split) for pc in asm.feed(decode_packet(d), T0 + k * 1e-4)]
    assert [(pc.t, [x.tracker for x in pc.poses], pc.close) for pc in pieces] == [
        (1.0, [head], True),
        (1.0, [hand], True),
    ]
    assert asm.shape == "bundle"


def test_a_device_on_pos_and_pos_local_is_not_a_repeat():
    from pythonosc.osc_message_builder import OscMessageBuilder

    def msg(address, *args):
        m = OscMessageBuilder(address)
        for a in args:
            m.add_arg(a)
        return decode_packet(m.build().dgram)

    asm = FrameAssembler(clock_origin=T0)
    frames = {}
    for i in range(5):
        w = T0 + i / 60.0
        stream = [msg("/VMC/Ext/T", i / 60.0)] + [
            msg(a, "HMD", float(i), 0.0, 0.0, 0.0, 0.0, 0.0, 1.0)
            for a in ("/VMC/Ext/Hmd/Pos", "/VMC/Ext/Hmd/Pos/Local")
        ]
        for j, p in enumerate(stream):
            for pc in asm.feed(p, w + j * SPACING, w + j * SPACING):
                frames.setdefault(round(pc.t * 60), []).extend(x.address for x in pc.poses)
    assert asm.untimed == 0 and asm.shape == "time-first"
    assert frames == {i: ["/VMC/Ext/Hmd/Pos", "/VMC/Ext/Hmd/Pos/Local"] for i in range(5)}
