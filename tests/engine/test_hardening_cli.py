"""Hostile input through the CLI (the hostile-input audit): every case ends in one line naming the
file/flag/field and the allowed range, exit status 2, before any expensive work."""

from __future__ import annotations

import json
import os
import re
from pathlib import Path

import pytest

from engine.cli.main import main

REPO = Path(__file__).resolve().parents[2]
EX = REPO / "assets" / "clips" / "example.bvh"


def run(argv: list[str], capsys) -> tuple[int, str, str]:
    try:
        rc = main([str(a) for a in argv])
    except SystemExit as exc:  # argparse's errors
        rc = exc.code
    out, err = capsys.readouterr()
    return rc, out, err


def assert_one_line_error(rc: int, err: str, *needles: str) -> None:
    lines = [line for line in err.splitlines() if line.strip()]
    assert rc == 2, err
    assert len(lines) == 1, f"expected one line, got {len(lines)}: {err[:500]}"
    assert "Traceback" not in err
    for n in needles:
        assert n in lines[0], lines[0]


def _clip(tmp_path: Path, name: str, edit) -> Path:
    lines = EX.read_text().splitlines()
    motion = next(i for i, s in enumerate(lines) if s.strip().upper() == "MOTION")
    path = tmp_path / name
    path.write_text("\n".join(edit(lines, motion)) + "\n")
    return path


def _with_frame_time(value: str):
    def edit(lines, m):
        lines[m + 2] = f"Frame Time: {value}"
        return lines

    return edit


def _offsets(fn):
    def edit(lines, m):
        out = []
        for line in lines[:m]:
            hit = re.match(r"(\s*OFFSET)\s+(\S+)\s+(\S+)\s+(\S+)", line)
            out.append(hit.group(1) + " " + " ".join(fn(float(v)) for v in hit.groups()[1:]) if hit else line)
        return out + lines[m:]

    return edit


@pytest.fixture
def no_solve(monkeypatch):
    """Fail the test if a command gets as far as reconstructing."""
    import engine.methods

    def boom(*a, **k):
        raise AssertionError("the solve started although the input was invalid")

    monkeypatch.setattr(engine.methods, "run_method", boom)


# -- 2: sensor lists without a 6-DoF sensor --------------------------------------------


def test_reconstruct_with_only_3dof_sensors_runs(tmp_path, capsys):
    rc, out, err = run(
        [
            "reconstruct",
            EX,
            "--out",
            tmp_path / "o.bvh",
            "--sensors",
            "6x3dof",
            "--max-frames",
            "2",
            "--iterations",
            "2",
            "--no-progress",
        ],
        capsys,
    )
    assert rc == 0, err
    assert (tmp_path / "o.bvh").is_file()


# -- 3, 9: numbers that blow up memory or crash ------------------------------------------


@pytest.mark.parametrize("value", ["100", "10", "1e-320"])
def test_frame_time_outside_1_to_1000_fps_is_refused(tmp_path, capsys, value):
    clip = _clip(tmp_path, "ft.bvh", _with_frame_time(value))
    rc, _, err = run(["info", clip], capsys)
    assert_one_line_error(rc, err, "ft.bvh:", "Frame Time", "allowed: a number in [0.001, 1] s")


@pytest.mark.parametrize("value", ["0.001", "nan", "inf", "1e-300"])
def test_info_fps_is_range_checked(capsys, value):
    rc, _, err = run(["info", "--fps", value, EX], capsys)
    assert_one_line_error(rc, err, "--fps", "[1, 1000] frames/s")


def test_huge_frame_count_in_the_header_is_refused(tmp_path, capsys):
    def edit(lines, m):
        lines[m + 1] = "Frames: " + "9" * 5001
        return lines

    rc, _, err = run(["info", _clip(tmp_path, "many.bvh", edit)], capsys)
    assert_one_line_error(rc, err, "many.bvh:", "Frames", "10000000")


def test_canonical_frame_count_is_limited_before_resampling(tmp_path, capsys, monkeypatch):
    from engine import validation

    monkeypatch.setitem(validation.SKELETON, "canonical frames", validation.Num(1, 1000, integer=True))
    frames = int(re.search(r"^Frames:\s*(\d+)", EX.read_text(), re.M).group(1))
    canonical = (frames - 1) * 60 + 1  # frames - 1 seconds at 1 fps, sampled at 60 fps
    rc, _, err = run(["info", "--fps", "1", EX], capsys)
    assert_one_line_error(rc, err, "example.bvh: at 1 frames/s", f"frames at 60 fps = {canonical}")


@pytest.mark.parametrize(
    "args, needles",
    [
        (["--set", "threads=100000"], ("threads = 100000", "[0, 64]")),
        (["--set", "threads=5000"], ("threads = 5000",)),
        (["--set", "past_window=1000000000"], ("past_window", "[1, 1024]")),
        (["--iterations", "1000000000"], ("--iterations", "[1, 10000]")),
        (["--seed", "-1"], ("--seed", "[0, 4294967295]")),
        (["--max-frames", "0"], ("--max-frames",)),
    ],
)
def test_reconstruct_numbers_are_range_checked_before_the_solve(tmp_path, capsys, no_solve, args, needles):
    rc, _, err = run(["reconstruct", EX, "--out", tmp_path / "o.bvh", "--no-progress", *args], capsys)
    assert_one_line_error(rc, err, *needles)


@pytest.mark.parametrize(
    "args, flag",
    [
        (["--faulty", "nan"], "--faulty"),
        (["--noise-pos", "nan"], "--noise-pos"),
        (["--noise-pos", "-1"], "--noise-pos"),
        (["--noise-rot", "inf"], "--noise-rot"),
        (["--seed", "-1"], "--seed"),
    ],
)
def test_evaluate_numbers_are_range_checked(capsys, no_solve, args, flag):
    rc, _, err = run(["evaluate", EX, "--no-progress", *args], capsys)
    assert_one_line_error(rc, err, flag, "allowed:")


def test_outputs_are_checked_before_any_work(tmp_path, capsys, no_solve):
    rc, _, err = run(["reconstruct", EX, "--out", tmp_path, "--no-progress"], capsys)
    assert_one_line_error(rc, err, "--out", "is a folder")
    rc, _, err = run(["reconstruct", EX, "--out", "/proc/o.bvh", "--no-progress"], capsys)
    assert_one_line_error(rc, err, "--out /proc/o.bvh", "cannot write")
    rc, _, err = run(["evaluate", EX, "--json", tmp_path, "--no-progress"], capsys)
    assert_one_line_error(rc, err, "--json", "is a folder")


# -- 5: special files --------------------------------------------------------------------


def test_fifo_dev_zero_and_symlink_loop_fail_at_once(tmp_path, capsys, no_solve):
    os.mkfifo(tmp_path / "x.bvh")  # opening it would block forever
    (tmp_path / "zero.bvh").symlink_to("/dev/zero")  # reading it would never end
    (tmp_path / "a.bvh").symlink_to(tmp_path / "b.bvh")
    (tmp_path / "b.bvh").symlink_to(tmp_path / "a.bvh")
    for name, reason in (
        ("x.bvh", "not a regular file"),
        ("zero.bvh", "not a regular file"),
        ("a.bvh", "symbolic links"),
    ):
        rc, _, err = run(["info", tmp_path / name], capsys)
        assert_one_line_error(rc, err, name, reason)
        rc, _, err = run(["reconstruct", tmp_path / name, "--out", tmp_path / "o.bvh"], capsys)
        assert_one_line_error(rc, err, name, reason)


# -- 6: scene files ------------------------------------------------------------------------


@pytest.mark.parametrize(
    "content, needle",
    [
        (b'{"constraints": ' + b"[" * 100_000 + b"]" * 100_000 + b"}", "nested"),
        (b'{"settings": {"iterations": ' + b"9" * 5001 + b"}}", "too many digits"),
        (b'{"settings": {"root_anchor": "caf\xe9"}}', "not UTF-8"),
        (b'{"constraints": [{"kind": ["look_at"]}]}', "unknown constraint kind"),
        (b'{"constraints": [{"kind": "sensor", "joint": "lwrist", "dof": 6.5}]}', "'dof' must be a whole number"),
        (b'{"settings": {"threads": 5000}}', "threads = 5000"),
        (b'{"settings": {"past_window": 1000000000}}', "past_window"),
        (b'{"constraints": [{"kind": "pin", "joint": "lwrist", "position": [1e400, 0, 0]}]}', "too large"),
    ],
)
def test_bad_scenes_are_one_line(tmp_path, capsys, no_solve, content, needle):
    scene = tmp_path / "scene.json"
    scene.write_bytes(content)
    rc, _, err = run(["reconstruct", EX, "--out", tmp_path / "o.bvh", "--scene", scene], capsys)
    assert_one_line_error(rc, err, "scene.json", needle)


# -- 7: manifest.json beside a clip ---------------------------------------------------------


@pytest.mark.parametrize(
    "manifest, needle",
    [
        ("[]", "a manifest is a JSON object"),
        ('{"files": 3}', "'files' must be a list"),
        ('{"files": [{"path": "a.bvh", "fps": "abc"}]}', "fps = 'abc' is not a number"),
        ('{"files": [{"path": "a.bvh", "fps": NaN}]}', "NaN"),
        ('{"files": [{"path": "a.bvh", "fps": 0.01}]}', "fps = 0.01 is out of range"),
        ('{"files": ["a.bvh"]}', "files[0] must be an object"),
    ],
)
def test_bad_manifest_is_one_line(tmp_path, capsys, manifest, needle):
    (tmp_path / "a.bvh").write_bytes(EX.read_bytes())
    (tmp_path / "manifest.json").write_text(manifest)
    rc, _, err = run(["info", tmp_path / "a.bvh"], capsys)
    assert_one_line_error(rc, err, "manifest.json", needle)


# -- 8: values the parser accepts but no solver can use --------------------------------------


def test_implausible_skeletons_and_roots_are_refused(tmp_path, capsys, no_solve):
    zero = _clip(tmp_path, "zero.bvh", _offsets(lambda v: "0"))
    huge = _clip(tmp_path, "huge.bvh", _offsets(lambda v: "9999" if v else "0"))

    def far_root(lines, m):
        row = lines[m + 3].split()
        row[0] = "1e308"
        lines[m + 3] = " ".join(row)
        return lines

    far = _clip(tmp_path, "far.bvh", far_root)
    for clip, needle in ((zero, "height = 0.0"), (huge, "height = "), (far, "largest root coordinate")):
        rc, _, err = run(["info", clip], capsys)
        assert_one_line_error(rc, err, clip.name, needle)
        rc, _, err = run(["reconstruct", clip, "--out", tmp_path / "o.bvh", "--max-frames", "2"], capsys)
        assert_one_line_error(rc, err, clip.name, needle)


def test_vae_with_non_finite_weights_is_refused(tmp_path, capsys, no_solve):
    import torch

    payload = torch.load(REPO / "assets/models/vae.pt", map_location="cpu", weights_only=True)
    next(t for t in payload["state_dict"].values() if t.is_floating_point()).fill_(float("nan"))
    torch.save(payload, tmp_path / "nan.pt")
    rc, _, err = run(["reconstruct", EX, "--out", tmp_path / "o.bvh", "--vae", tmp_path / "nan.pt"], capsys)
    assert_one_line_error(rc, err, "nan.pt", "NaN or infinite")
    assert not (tmp_path / "o.bvh").exists()


# -- 10: messages -------------------------------------------------------------------------------


def test_unknown_rig_is_one_line(tmp_path, capsys):
    def rename(lines, m):
        return [line.replace("ROOT ", "ROOT zz").replace("JOINT ", "JOINT zz") for line in lines[:m]] + lines[m:]

    rc, _, err = run(["info", _clip(tmp_path, "odd.bvh", rename)], capsys)
    assert_one_line_error(rc, err, "odd.bvh", "skeleton")


def test_bad_tokens_are_cut_short(tmp_path, capsys):
    token = "q" * 1_000_000
    rc, _, err = run(["reconstruct", EX, "--out", tmp_path / "o.bvh", "--sensors", token], capsys)
    assert_one_line_error(rc, err)
    assert len(err) < 1000
    rc, _, err = run(["info", "--fps", token, EX], capsys)  # argparse's own error
    assert_one_line_error(rc, err, "--fps")
    assert len(err) < 1000


def test_weights_errors_do_not_advise_turning_safety_off(tmp_path, capsys, no_solve):
    (tmp_path / "junk.pt").write_bytes(b"not a zip file at all")
    rc, _, err = run(["reconstruct", EX, "--out", tmp_path / "o.bvh", "--vae", tmp_path / "junk.pt"], capsys)
    assert_one_line_error(rc, err, "junk.pt")
    assert "weights_only" not in err


def test_json_output_of_a_good_scene_still_loads(tmp_path, capsys):
    """The checks do not refuse what the project writes itself."""
    from engine.scene import load_scene, save_scene

    save_scene(tmp_path / "s.json", [], {"threads": 1, "past_window": 16})
    constraints, settings = load_scene(tmp_path / "s.json")
    assert settings.threads == 1 and constraints == []
    assert json.loads((tmp_path / "s.json").read_text())["format"] == "dragposer-scene"


# -- 3: long files are streamed ----------------------------------------------------------------


def _long_clip(tmp_path: Path, frames: int) -> Path:
    def repeat(lines, m):
        rows = [r for r in lines[m + 3 :] if r.strip()]
        lines[m + 1] = f"Frames: {frames}"
        return lines[: m + 3] + [rows[i % len(rows)] for i in range(frames)]

    return _clip(tmp_path, "long.bvh", repeat)


def test_info_and_reconstruct_keep_only_the_start_of_a_long_file(tmp_path, capsys, monkeypatch):
    import engine.motion.bvh
    import engine.motion.retarget as rt
    import engine.motion.source_file

    kept = []
    real = engine.motion.bvh.load_bvh

    def spy(path, max_frames=None):
        raw = real(path, max_frames)
        kept.append((raw.frames, raw.total_frames))
        return raw

    monkeypatch.setattr(engine.motion.source_file, "load_bvh", spy)
    monkeypatch.setattr(engine.motion.bvh, "load_bvh", spy)
    monkeypatch.setattr(rt, "ALIGN_FRAMES", 1000)
    clip = _long_clip(tmp_path, 3000)
    rc, out, err = run(["info", clip], capsys)
    assert rc == 0, err
    assert "3000 frames at 60 fps" in out
    assert kept[-1] == (1000, 3000)
    rc, out, err = run(
        [
            "reconstruct",
            clip,
            "--out",
            tmp_path / "o.bvh",
            "--max-frames",
            "2",
            "--iterations",
            "1",
            "--method",
            "ik",
            "--no-progress",
        ],
        capsys,
    )
    assert rc == 0, err
    assert kept[-1] == (1000, 3000)
