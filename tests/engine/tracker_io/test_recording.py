"""The JSON Lines tracker recording: round trip, atomic streaming writes, clear errors,
and replay into the solver's input."""

from __future__ import annotations

import json

import numpy as np
import pytest

from engine.errors import UserError
from engine.tracker_io.coords import from_project
from engine.tracker_io.recording import RecordingWriter, header, read_recording, replay, write_recording
from engine.tracker_io.trackers import TrackerMapping, TrackerSample, TrackerState

IDENT = np.array([1.0, 0.0, 0.0, 0.0])


def _samples(n: int = 5) -> list[TrackerSample]:
    out = []
    for i in range(n):
        t = i / 60
        out.append(TrackerSample(t, "head", np.array([0.1 * i, 0.0, 1.6]), IDENT))
        out.append(
            TrackerSample(
                t, "left_hand", np.array([0.3, -0.2, 1.0 + 0.01 * i]), np.array([0.7071068, 0.0, 0.0, 0.7071068])
            )
        )
    return out


def test_round_trip_keeps_every_sample(tmp_path):
    path = tmp_path / "rec.jsonl"
    write_recording(path, _samples(), 60.0, source="test")
    rec = read_recording(path)
    assert rec.header["format"] == "dragposer-trackers" and rec.fps == 60.0
    assert len(rec.samples) == 10 and rec.mapping.slot("head") == "upperneck"
    for a, b in zip(rec.samples, _samples()):
        assert a.tracker == b.tracker and a.t == pytest.approx(b.t, abs=1e-6)
        np.testing.assert_allclose(a.position, b.position, atol=1e-6)
        np.testing.assert_allclose(a.rotation, b.rotation, atol=1e-6)
    line = json.loads(path.read_text().splitlines()[1])
    assert set(line) == {"t", "tracker", "slot", "pos", "quat", "valid"}


def test_streaming_writer_is_atomic(tmp_path):
    path = tmp_path / "rec.jsonl"
    path.write_text("old\n")
    w = RecordingWriter(path, header(60.0, TrackerMapping(), "test"), flush_every=1)
    for s in _samples():
        w.write(s, "upperneck")
    assert path.read_text() == "old\n"  # nothing replaced while streaming
    temps = [p for p in tmp_path.iterdir() if p.name.startswith(".rec.jsonl.")]
    assert len(temps) == 1 and temps[0].read_text().count("\n") == 11  # flushed as it goes
    w.abort()
    assert path.read_text() == "old\n" and len(list(tmp_path.iterdir())) == 1
    with RecordingWriter(path, header(60.0, TrackerMapping(), "test")) as w:
        w.write(_samples()[0])
    assert len(read_recording(path).samples) == 1 and len(list(tmp_path.iterdir())) == 1


@pytest.mark.parametrize(
    "line, message",
    [
        ("not json", r":3: not JSON"),
        ('{"t": "a", "tracker": "head", "pos": [0,0,0], "quat": [1,0,0,0]}', r":3: field 't'"),
        ('{"t": 1, "tracker": "", "pos": [0,0,0], "quat": [1,0,0,0]}', r":3: field 'tracker'"),
        ('{"t": 1, "tracker": "head", "pos": [0,0], "quat": [1,0,0,0]}', r":3: field 'pos' must be a list of 3"),
        ('{"t": 1, "tracker": "head", "pos": [0,0,0], "quat": [0,0,0,0]}', r":3: field 'quat' is zero"),
        ('{"t": 1, "tracker": "head", "pos": [0,0,0], "quat": [1,0,0,0], "valid": 1}', r":3: field 'valid'"),
    ],
)
def test_bad_lines_name_file_line_and_field(tmp_path, line, message):
    path = tmp_path / "bad.jsonl"
    good = json.dumps({"t": 0, "tracker": "head", "pos": [0, 0, 1], "quat": [1, 0, 0, 0]})
    path.write_text(json.dumps(header(60, TrackerMapping(), "x")) + "\n" + good + "\n" + line + "\n")
    with pytest.raises(UserError, match=f"bad.jsonl{message}"):
        read_recording(path)


def test_bad_headers(tmp_path):
    path = tmp_path / "h.jsonl"
    path.write_text('{"format": "something else"}\n')
    with pytest.raises(UserError, match="h.jsonl:1: not a tracker recording"):
        read_recording(path)
    path.write_text(json.dumps({**header(60, TrackerMapping(), "x"), "fps": 0}) + "\n")
    with pytest.raises(UserError, match="h.jsonl:1: field 'fps'"):
        read_recording(path)
    path.write_text("")
    with pytest.raises(UserError, match="empty file"):
        read_recording(path)
    with pytest.raises(UserError, match="missing.jsonl: cannot read tracker recording: not found"):
        read_recording(tmp_path / "missing.jsonl")


def test_a_unity_recording_is_converted_on_reading(tmp_path):
    p = np.array([0.2, -0.5, 1.4])
    q = np.array([0.9238795, 0.0, 0.0, 0.3826834])
    pu, qu = from_project(p, q, "unity")
    head = {**header(60, TrackerMapping(), "x"), "convention": "unity"}
    path = tmp_path / "u.jsonl"
    path.write_text(
        json.dumps(head)
        + "\n"
        + json.dumps({"t": 0, "tracker": "head", "pos": pu.tolist(), "quat": qu.tolist()})
        + "\n"
    )
    s = read_recording(path).samples[0]
    np.testing.assert_allclose(s.position, p, atol=1e-9)
    np.testing.assert_allclose(s.rotation, q, atol=1e-9)


def test_replay_holds_lost_trackers_and_times_them_out():
    samples = [TrackerSample(i / 60, "head", np.array([0, 0, 1.6 + i]), IDENT) for i in range(30)]
    samples += [TrackerSample(0.0, "hips", np.array([0, 0, 1.0]), IDENT)]  # then silent
    samples += [TrackerSample(0.0, "puck9", np.array([0, 0, 0.0]), IDENT)]  # not mapped
    tracking, times = replay(samples, TrackerMapping(), timeout_s=0.1)
    assert tracking.joints == ("root", "upperneck") and len(tracking) == 30
    np.testing.assert_allclose(times, np.arange(30) / 60)
    hips = tracking.connected[:, 0]
    assert hips[:7].all() and not hips[7:].any()  # 6/60 s <= 0.1 s < 7/60 s
    np.testing.assert_allclose(tracking.positions[:, 0, 2], 1.0)  # held while lost
    assert tracking.connected[:, 1].all()


def test_state_counts_duplicates_and_late_samples_without_using_them():
    st = TrackerState()
    assert st.update(TrackerSample(1.0, "head", np.array([0, 0, 1.0]), IDENT)) == "ok"
    assert st.update(TrackerSample(1.0, "head", np.array([0, 0, 9.0]), IDENT)) == "duplicate"
    assert st.update(TrackerSample(0.5, "head", np.array([0, 0, 9.0]), IDENT)) == "late"
    r = st.frame(0, 1.0).readings["upperneck"]
    assert r.connected and r.position[2] == 1.0
    assert st.update(TrackerSample(1.1, "head", np.zeros(3), IDENT, valid=False)) == "ok"
    assert not st.frame(1, 1.1).readings["upperneck"].connected


def test_mapping_parse_and_errors(tmp_path):
    m = TrackerMapping.parse("hmd=upperneck, puck1=root, puck2=lankle:3")
    assert m.slot("puck1") == "root" and m.dof_of("puck2") == 3 and m.slot("head") is None
    with pytest.raises(UserError, match="unknown joint 'elbow'"):
        TrackerMapping.parse("a=elbow")
    with pytest.raises(UserError, match="more than one tracker"):
        TrackerMapping.parse("a=root,b=root")
    with pytest.raises(UserError, match="expected NAME=JOINT"):
        TrackerMapping.parse("root")
    f = tmp_path / "map.json"
    f.write_text(json.dumps({"slots": {"hmd": "upperneck"}, "dof": {"hmd": 6}}))
    assert TrackerMapping.parse(str(f)).slot("hmd") == "upperneck"
    f.write_text("[]")
    with pytest.raises(UserError, match="map.json: not a tracker mapping"):
        TrackerMapping.parse(str(f))


def _recording_text(n: int = 3) -> str:
    lines = [json.dumps(header(60, TrackerMapping(), "x"))]
    lines += [json.dumps({"t": i / 60, "tracker": "head", "pos": [0, 0, 1.6], "quat": [1, 0, 0, 0]}) for i in range(n)]
    return "\n".join(lines) + "\n"


def test_bad_files_are_refused_through_the_validation_layer(tmp_path, monkeypatch):
    """Truncated, binary, not UTF-8, one huge line, too large, not a file: one line each,
    naming the file (and the line)."""
    from engine import validation

    text = _recording_text()
    cases = {
        "cut.jsonl": (text[: len(text) - 20].encode(), r"cut.jsonl:4: not JSON"),
        "bin.jsonl": (text.encode()[:80] + b"\0\x01\x02" + text.encode()[80:], r"bin.jsonl:1: binary data"),
        "latin.jsonl": (
            text.encode() + '{"tracker": "tête"}\n'.encode("latin-1"),
            r"latin.jsonl:5: not UTF-8 text \(byte 0xea\)",
        ),
        "long.jsonl": (
            text.encode() + b"[" * (validation.MAX_LINE_BYTES + 10),
            r"long.jsonl:5: line longer than 65,536 bytes",
        ),
    }
    for name, (data, message) in cases.items():
        (tmp_path / name).write_bytes(data)
        with pytest.raises(UserError, match=message):
            read_recording(tmp_path / name)
    monkeypatch.setitem(validation.MAX_BYTES, "tracker recording", 100)
    (tmp_path / "big.jsonl").write_text(text)
    with pytest.raises(
        UserError, match=r"big.jsonl: cannot read tracker recording: \d+ bytes is larger than the limit of 100"
    ):
        read_recording(tmp_path / "big.jsonl")
    with pytest.raises(UserError, match=r": cannot read tracker recording: is a folder"):
        read_recording(tmp_path)


def test_tracker_mapping_files_go_through_the_validation_layer(tmp_path):
    bad = tmp_path / "map.json"
    bad.write_bytes(b'{"slots": {"head": "upperneck"},\n "dof": \xff}')
    with pytest.raises(UserError, match=r"map.json:2: tracker mapping is not UTF-8"):
        TrackerMapping.load(bad)
    bad.write_text('{"slots": {"head": "upperneck"},\n "dof": [}')
    with pytest.raises(UserError, match=r"map.json:2: invalid JSON in tracker mapping"):
        TrackerMapping.load(bad)
    bad.write_text('{"slots": ["head"]}')
    with pytest.raises(UserError, match=r"map.json: not a tracker mapping"):
        TrackerMapping.load(bad)
    with pytest.raises(UserError, match=r"cannot read tracker mapping: not found"):
        TrackerMapping.load(tmp_path / "none.json")
