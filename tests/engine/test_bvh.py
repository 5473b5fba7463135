"""BVH reading and writing: validation with file and line, fuzzing, atomic save, round trips."""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from pymotion.io.bvh import BVH as PymotionBVH
from pymotion.rotations import quat_np

from engine import skeleton as sk
from engine.errors import BVHError
from engine.kinematics.fk import fk
from engine.motion.bvh import RawBVH, load_bvh, save_motion_bvh
from engine.motion.clip import Motion

# A three-joint clip; the line numbers below are the ones the error tests expect.
VALID = """\
HIERARCHY
ROOT hips
{
\tOFFSET 0.0 0.0 0.0
\tCHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation
\tJOINT spine
\t{
\t\tOFFSET 0.0 0.1 0.0
\t\tCHANNELS 3 Zrotation Xrotation Yrotation
\t\tEnd Site
\t\t{
\t\t\tOFFSET 0.0 0.2 0.0
\t\t}
\t}
\tJOINT leg
\t{
\t\tOFFSET 0.1 -0.1 0.0
\t\tCHANNELS 3 Xrotation Yrotation Zrotation
\t}
}
MOTION
Frames: 3
Frame Time: 0.0333333
0.0 1.0 2.0 10.0 20.0 30.0 5.0 -5.0 45.0 1.0 2.0 3.0
0.1 1.1 2.1 11.0 21.0 31.0 6.0 -6.0 46.0 2.0 3.0 4.0
0.2 1.2 2.2 12.0 22.0 32.0 7.0 -7.0 47.0 3.0 4.0 5.0
"""
LINES = VALID.splitlines()


def edited(changes: dict[int, str | None], cut: int | None = None) -> str:
    """VALID with 1-based lines replaced (None deletes them), optionally cut after line ``cut``."""
    out = [changes.get(n, line) for n, line in enumerate(LINES, start=1)][:cut]
    return "\n".join(line for line in out if line is not None) + "\n"


def write(tmp_path: Path, text: str, name: str = "clip.bvh") -> Path:
    path = tmp_path / name
    path.write_text(text)
    return path


def test_valid_file_is_read(tmp_path):
    raw = load_bvh(write(tmp_path, VALID))
    assert raw.names == ("hips", "spine", "leg")
    assert raw.parents == (-1, 0, 0)
    assert raw.channel_counts == (6, 3, 3)
    assert raw.frames == 3 and raw.fps == pytest.approx(30.0, rel=1e-5)
    assert list(raw.end_sites) == [1]
    np.testing.assert_allclose(raw.end_sites[1], [0.0, 0.2, 0.0])
    assert raw.rot_order.tolist() == [list("zxy"), list("zxy"), list("xyz")]
    np.testing.assert_allclose(raw.positions[:, 0], [[0, 1, 2], [0.1, 1.1, 2.1], [0.2, 1.2, 2.2]])
    np.testing.assert_allclose(raw.positions[:, 2], np.tile([0.1, -0.1, 0.0], (3, 1)))
    np.testing.assert_allclose(raw.rotations_deg[2, 1], [7.0, -7.0, 47.0])
    # quaternions agree with pymotion's own (slow) Euler conversion
    ref = quat_np.from_euler(np.radians(raw.rotations_deg), np.broadcast_to(raw.rot_order, (3, 3, 3)))
    np.testing.assert_allclose(np.abs((raw.local_quaternions() * ref).sum(-1)), 1.0, atol=1e-12)


def test_position_channels_in_any_order_are_stored_xyz(tmp_path):
    text = edited({5: "\tCHANNELS 6 Zposition Xposition Yposition Zrotation Xrotation Yrotation"})
    raw = load_bvh(write(tmp_path, text))
    np.testing.assert_allclose(raw.positions[0, 0], [1.0, 2.0, 0.0])


BAD_CASES = {
    # name: (edited text, line the error must name, words the message must contain)
    "missing HIERARCHY": (edited({1: None}), 1, "HIERARCHY"),
    "missing ROOT": (edited({2: "JOINT hips"}), 2, "ROOT"),
    "missing MOTION": (edited({}, cut=20), 20, "MOTION"),
    "missing closing brace": (edited({14: None}), 20, "'}'"),
    "extra closing brace": (edited({20: "}\n}"}), 21, "unbalanced"),
    "brace without joint": (edited({15: "\t{"}), 15, "unbalanced"),
    "non-numeric OFFSET": (edited({8: "\t\tOFFSET 0.0 abc 0.0"}), 8, "abc"),
    "short OFFSET": (edited({8: "\t\tOFFSET 0.0 0.1"}), 8, "3 numbers"),
    "long OFFSET": (edited({8: "\t\tOFFSET 0.0 0.1 0.2 0.3"}), 8, "3 numbers"),
    "nan OFFSET": (edited({17: "\t\tOFFSET nan 0 0"}), 17, "not finite"),
    "huge OFFSET": (edited({17: "\t\tOFFSET 1e5 0 0"}), 17, "large"),
    "CHANNELS 4": (edited({9: "\t\tCHANNELS 4 Zrotation Xrotation Yrotation Xposition"}), 9, "3 or 6"),
    "CHANNELS count vs names": (edited({9: "\t\tCHANNELS 3 Zrotation Xrotation"}), 9, "lists 2"),
    "unknown channel": (edited({9: "\t\tCHANNELS 3 Zrotation Wrotation Yrotation"}), 9, "Wrotation"),
    "repeated axis": (edited({9: "\t\tCHANNELS 3 Zrotation Zrotation Yrotation"}), 9, "one rotation channel"),
    "duplicated joint": (edited({15: "\tJOINT spine"}), 15, "line 6"),
    "zero frames": (edited({22: "Frames: 0", 24: None, 25: None, 26: None}), 22, "zero frames"),
    "negative frames": (edited({22: "Frames: -3"}), 22, "whole number"),
    "too few rows": (edited({22: "Frames: 5"}), 22, "only 3"),
    "too many rows": (edited({22: "Frames: 2"}), 26, "more data rows"),
    "short row": (edited({25: " ".join(LINES[24].split()[:-1])}), 25, "expected 12, got 11"),
    "long row": (edited({25: LINES[24] + " 1.0"}), 25, "expected 12, got 13"),
    "letters in row": (edited({24: LINES[23].replace("20.0", "2o.0")}), 24, "'2o.0'"),
    "nan in row": (edited({25: LINES[24].replace("6.0", "nan")}), 25, "not finite"),
    "inf in row": (edited({26: LINES[25].replace("7.0", "-inf")}), 26, "not finite"),
    "zero Frame Time": (edited({23: "Frame Time: 0"}), 23, "positive"),
    "negative Frame Time": (edited({23: "Frame Time: -0.01"}), 23, "positive"),
    "nan Frame Time": (edited({23: "Frame Time: nan"}), 23, "positive"),
    "text Frame Time": (edited({23: "Frame Time: fast"}), 23, "not a number"),
    "no Frame Time": (edited({}, cut=22), 22, "Frame Time"),
    "truncated hierarchy": (edited({}, cut=10), 10, "truncated"),
    "truncated row": (VALID[: VALID.rindex(" 4.0 ")], 26, "expected 12, got 10"),
    "empty file": ("", 1, "HIERARCHY"),
    # numbers are ASCII decimals: other digits (which int()/float() take unevenly) and '_' are errors
    "superscript Frames": (edited({22: "Frames: \u00b2"}), 22, "whole number"),
    "Arabic-Indic Frames": (edited({22: "Frames: \u0663"}), 22, "whole number"),
    "circled Frames": (edited({22: "Frames: \u2462"}), 22, "whole number"),
    "underscore Frames": (edited({22: "Frames: 0_3"}), 22, "whole number"),
    "Arabic-Indic Frame Time": (edited({23: "Frame Time: 0.0\u0663"}), 23, "not a number"),
    "underscore Frame Time": (edited({23: "Frame Time: 0.0_3"}), 23, "not a number"),
    "Arabic-Indic OFFSET": (edited({8: "\t\tOFFSET 0.0 \u0663\u0664 0.0"}), 8, "not a number"),
    "fullwidth OFFSET": (edited({8: "\t\tOFFSET \uff13 0.1 0.0"}), 8, "not a number"),
    "underscore OFFSET": (edited({8: "\t\tOFFSET 0.0 0.1 1_0"}), 8, "'1_0' is not a number"),
    "Arabic-Indic in a row": (edited({25: LINES[24].replace("6.0", "\u0663\u0664")}), 25, "is not a number"),
    "superscript in a row": (edited({24: LINES[23].replace("5.0", "5\u00b2")}), 24, "is not a number"),
    "underscore in a row": (edited({26: LINES[25].replace("47.0", "4_7.0")}), 26, "'4_7.0' is not a number"),
    "no-break space in a row": (edited({24: LINES[23].replace(" 1.0 ", "\u00a01.0 ", 1)}), 24, "U+00A0"),
}


@pytest.mark.parametrize("case", list(BAD_CASES))
def test_bad_input_names_file_and_line(tmp_path, case):
    text, line, words = BAD_CASES[case]
    path = write(tmp_path, text)
    with pytest.raises(BVHError) as err:
        load_bvh(path)
    assert err.value.path == str(path)
    assert err.value.line == line, str(err.value)
    assert words in err.value.message
    assert str(err.value).startswith(f"{path}:{line}: ")


def test_missing_file_is_a_bvh_error(tmp_path):
    with pytest.raises(BVHError, match="cannot read"):
        load_bvh(tmp_path / "nope.bvh")


# --- fuzzing: mutated files may fail, but only ever with BVHError -------------------------

_JUNK = [
    "{",
    "}",
    "nan",
    "inf",
    "-inf",
    "abc",
    "1e400",
    "0",
    "-1",
    "3",
    "6",
    "1e9",
    "JOINT",
    "ROOT",
    "End",
    "Site",
    "MOTION",
    "Frames:",
    "Frame Time:",
    "CHANNELS",
    "OFFSET",
    "Xrotation",
    "Yposition",
    "HIERARCHY",
    "\x00",
    "é",
    "",
    "1.5.2",
    "0x10",
    "--1",
    "+",
    ".",
]

_mutation = st.one_of(
    st.tuples(st.just("del_line"), st.integers(0, 40)),
    st.tuples(st.just("dup_line"), st.integers(0, 40)),
    st.tuples(st.just("swap_lines"), st.integers(0, 40), st.integers(0, 40)),
    st.tuples(st.just("del_token"), st.integers(0, 400)),
    st.tuples(st.just("dup_token"), st.integers(0, 400)),
    st.tuples(st.just("set_token"), st.integers(0, 400), st.sampled_from(_JUNK)),
    st.tuples(st.just("insert"), st.integers(0, 1200), st.sampled_from(_JUNK) | st.text(max_size=4)),
    st.tuples(st.just("truncate"), st.integers(0, 1200)),
)


def _mutate(text: str, op: tuple) -> str:
    kind, *args = op
    lines = text.split("\n")
    if kind in ("del_line", "dup_line", "swap_lines"):
        i = args[0] % len(lines)
        if kind == "del_line":
            del lines[i]
        elif kind == "dup_line":
            lines.insert(i, lines[i])
        else:
            k = args[1] % len(lines)
            lines[i], lines[k] = lines[k], lines[i]
        return "\n".join(lines)
    if kind in ("del_token", "dup_token", "set_token"):
        spots = [(n, t) for n, line in enumerate(lines) for t in range(len(line.split()))]
        if not spots:
            return text
        n, t = spots[args[0] % len(spots)]
        words = lines[n].split()
        if kind == "del_token":
            del words[t]
        elif kind == "dup_token":
            words.insert(t, words[t])
        else:
            words[t] = args[1]
        lines[n] = " ".join(words)
        return "\n".join(lines)
    pos = args[0] % (len(text) + 1)
    return text[:pos] + args[1] + text[pos:] if kind == "insert" else text[:pos]


def test_mutated_files_raise_only_bvh_errors(tmp_path):
    path = tmp_path / "fuzz.bvh"
    outcomes = {"error": 0, "loaded": 0}

    @settings(
        max_examples=250,
        deadline=None,
        database=None,
        suppress_health_check=[HealthCheck.too_slow, HealthCheck.filter_too_much],
    )
    @given(st.lists(_mutation, min_size=1, max_size=4))
    def throw(ops):
        text = VALID
        for op in ops:
            text = _mutate(text, op)
        path.write_bytes(text.encode("utf-8", errors="surrogatepass"))
        try:
            raw = load_bvh(path)
        except BVHError as exc:
            assert exc.path == str(path)
            outcomes["error"] += 1
            return
        outcomes["loaded"] += 1  # a harmless mutation: the result must still be sound
        assert isinstance(raw, RawBVH)
        assert np.isfinite(raw.rotations_deg).all() and np.isfinite(raw.positions).all()
        assert raw.rotations_deg.shape == raw.positions.shape == (raw.frames, len(raw.names), 3)
        assert np.isfinite(raw.local_quaternions()).all()

    throw()
    assert sum(outcomes.values()) >= 200
    assert outcomes["error"] > 100


# --- saving ------------------------------------------------------------------------------


def _fk_of(raw: RawBVH) -> np.ndarray:
    return fk(raw.local_quaternions(), raw.positions[:, 0], raw.offsets, raw.parents)[0]


def test_save_round_trip_synthetic(tmp_path, synthetic_motion):
    path = tmp_path / "out.bvh"
    save_motion_bvh(path, synthetic_motion)
    raw = load_bvh(path)
    assert raw.names == sk.JOINT_NAMES and raw.parents == sk.PARENTS
    assert raw.fps == pytest.approx(60.0, rel=1e-4)
    np.testing.assert_allclose(_fk_of(raw), synthetic_motion.positions(), atol=1e-4)
    assert sorted(raw.end_sites) == sorted(sk.JOINT_INDEX[n] for n in sk.END_SITES)
    umask = os.umask(0)
    os.umask(umask)
    assert path.stat().st_mode & 0o777 == 0o666 & ~umask  # not mkstemp's owner-only 0600


def test_saved_channel_layout_is_blender_style(tmp_path, synthetic_motion):
    big = Motion(synthetic_motion.local_rot, synthetic_motion.root_pos, sk.Skeleton.canonical(1.2))
    path = tmp_path / "out.bvh"
    save_motion_bvh(path, big)
    lines = [line.split() for line in path.read_text().splitlines()]
    channels = [words[1:] for words in lines if words[:1] == ["CHANNELS"]]
    assert channels[0] == ["6", "Xposition", "Yposition", "Zposition", "Zrotation", "Xrotation", "Yrotation"]
    assert all(c == ["3", "Zrotation", "Xrotation", "Yrotation"] for c in channels[1:])
    assert len(channels) == sk.NUM_JOINTS
    raw = load_bvh(path)
    np.testing.assert_allclose(raw.end_sites[sk.JOINT_INDEX["ltoe"]], sk.END_SITES["ltoe"] * 1.2, atol=1e-5)
    np.testing.assert_allclose(raw.offsets[1:], big.skeleton.offsets[1:], atol=1e-6)


def test_save_round_trip_shared_clip(tmp_path, shared_mocap):
    src = load_bvh(shared_mocap / "dragposer" / "example_2.bvh")
    # pymotion's own reader agrees with ours on the real file
    ref = PymotionBVH()
    ref.load(str(shared_mocap / "dragposer" / "example_2.bvh"))
    ref_rot, ref_pos, *_ = ref.get_data()
    np.testing.assert_allclose(np.abs((src.local_quaternions() * ref_rot).sum(-1)), 1.0, atol=1e-6)
    np.testing.assert_allclose(src.positions, ref_pos)

    motion = Motion(src.local_quaternions(), src.positions[:, 0], sk.Skeleton(src.offsets), src.fps, "example_2")
    path = tmp_path / "example_2_out.bvh"
    save_motion_bvh(path, motion)
    back = load_bvh(path)
    assert back.frames == src.frames
    np.testing.assert_allclose(_fk_of(back), _fk_of(src), atol=1e-4)


def test_failed_save_keeps_the_old_file_and_leaves_no_temp(tmp_path, synthetic_motion, monkeypatch):
    path = tmp_path / "out.bvh"
    path.write_text("previous contents")

    def broken_save(self, filename):
        Path(filename).write_text("HIERARCHY\nROOT root\n{\n")  # half a file, then a crash
        raise OSError("disk full")

    monkeypatch.setattr(PymotionBVH, "save", broken_save)
    with pytest.raises(OSError, match="disk full"):
        save_motion_bvh(path, synthetic_motion)
    assert path.read_text() == "previous contents"
    assert os.listdir(tmp_path) == ["out.bvh"]


def test_non_finite_motion_is_not_written(tmp_path, synthetic_motion):
    rot = synthetic_motion.local_rot.copy()
    rot[3, 5, 0] = np.nan
    with pytest.raises(ValueError, match="NaN"):
        save_motion_bvh(tmp_path / "out.bvh", Motion(rot, synthetic_motion.root_pos))
    assert list(tmp_path.iterdir()) == []


def test_only_the_kept_frames_are_held_but_every_row_is_checked(tmp_path):
    from engine.motion.bvh_parser import parse_bvh_text

    lines = VALID.splitlines()
    path = write(tmp_path, VALID)
    full, head = load_bvh(path), load_bvh(path, max_frames=2)
    assert head.frames == 2 and head.total_frames == full.frames == full.total_frames
    assert np.array_equal(head.rotations_deg, full.rotations_deg[:2])
    bad = "\n".join(lines[:-1] + ["0 " * (len(lines[-1].split()) - 1) + "oops"]) + "\n"
    with pytest.raises(BVHError, match="'oops' is not a number"):
        load_bvh(write(tmp_path, bad), max_frames=1)  # a bad last row fails even when not kept
    claims = VALID.replace(f"Frames: {full.frames}", "Frames: 9000000")
    with pytest.raises(BVHError, match="only .* data rows follow"):
        parse_bvh_text("x.bvh", claims)  # allocates for what the text can hold, not for 9 million


def test_a_huge_hierarchy_is_refused_before_tokenising(tmp_path, monkeypatch):
    import engine.motion.bvh_parser as bp

    monkeypatch.setattr(bp, "MAX_HEADER", 100)
    with pytest.raises(BVHError, match="HIERARCHY section is longer than 100"):
        load_bvh(write(tmp_path, VALID))
