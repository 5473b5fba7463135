"""``--rig-map MAP.toml`` files go through the validation layer: size, type, encoding,
syntax and every field's type; each failure is one line naming the file (and line/field)."""

from __future__ import annotations

import json

import pytest

from engine import validation
from engine.errors import UserError
from engine.motion.bvh import load_bvh
from engine.motion.rigs import resolve_rig

from .rig_fixtures import write_family_bvh


@pytest.fixture(scope="module")
def clip(tmp_path_factory):
    from engine.cli.rig import write_suggestion

    folder = tmp_path_factory.mktemp("rigmap")
    bvh = write_family_bvh(folder / "lafan.bvh", "lafan", frames=30)
    good = folder / "good.toml"
    assert write_suggestion(bvh, good)
    return bvh, good.read_text()


@pytest.mark.parametrize(
    "edit, message",
    [
        (lambda t: t[: t.index("[joints]")], r"map.toml: rig mapping lacks a \[joints\] table"),  # truncated
        (lambda t: t[: t.index('"LeftLeg"') + 4], r"map.toml: invalid TOML in rig mapping \(Unterminated string"),
        (
            lambda t: t.replace('lknee = "LeftLeg"', "lknee = 3"),
            r"map.toml: rig mapping: field 'joints.lknee' must be a joint name \(a non-empty string\), got 3",
        ),
        (lambda t: t.replace('lknee = "LeftLeg"', 'lknee = ""'), r"field 'joints.lknee' must be a joint name"),
        (
            lambda t: "units_to_m = 'abc'\n" + t.replace("units_to_m", "# was"),
            r"map.toml: rig mapping: units_to_m = 'abc' is not a number; allowed: a number in \(1e-06, 1000\]",
        ),
        (lambda t: "units_to_m = -1.0\n" + t.replace("units_to_m", "# was"), r"units_to_m = -1.0 is out of range"),
        (lambda t: t.replace("skip_frames = 0", "skip_frames = 2.5"), r"skip_frames = 2.5 is not a whole number"),
        (
            lambda t: t.replace("skip_frames = 0", 'skip_frames = 0\nalign = "yes"'),
            r"field 'align' must be true or false",
        ),
        (lambda t: "colour = 'red'\n" + t, r"rig mapping: unknown field\(s\) 'colour'"),
        (lambda t: t + "[joints\n", r"map.toml: invalid TOML in rig mapping \(.*line \d+"),
        (lambda t: t.replace("[landmarks]", "landmarks = 3\n[other]"), r"unknown field\(s\) 'other'"),
    ],
)
def test_bad_mapping_files_name_file_and_field(clip, tmp_path, edit, message):
    bvh, good = clip
    bad = tmp_path / "map.toml"
    bad.write_text(edit(good))
    with pytest.raises(UserError, match=message):
        resolve_rig(load_bvh(bvh), bad)


def test_binary_huge_and_special_files_are_refused_before_parsing(clip, tmp_path, monkeypatch):
    bvh, good = clip
    raw = load_bvh(bvh)
    binary = tmp_path / "bin.toml"
    binary.write_bytes(b'[joints]\nroot = "Hips"\n\xff\xfe\x00\x01')
    with pytest.raises(UserError, match=r"bin.toml:3: rig mapping is not UTF-8 text \(byte 0xff\)"):
        resolve_rig(raw, binary)
    monkeypatch.setitem(validation.MAX_BYTES, "rig mapping", 64)
    big = tmp_path / "big.toml"
    big.write_text(good)
    with pytest.raises(
        UserError, match=r"big.toml: cannot read rig mapping: [\d,]+ bytes is larger than the limit of 64"
    ):
        resolve_rig(raw, big)
    with pytest.raises(UserError, match=r"cannot read rig mapping: is a folder"):
        resolve_rig(raw, tmp_path)


def test_info_json_reports_a_bad_mapping_as_one_object(clip, tmp_path, capsys):
    from engine.cli.main import main

    bvh, good = clip
    bad = tmp_path / "m.toml"
    bad.write_text(good.replace('lknee = "LeftLeg"', "lknee = 3"))
    assert main(["info", str(bvh), "--json", "--rig-map", str(bad)]) == 2
    out = json.loads(capsys.readouterr().out)
    assert "m.toml" in out["error"] and "joints.lknee" in out["error"]


@pytest.mark.parametrize(
    "command",
    [
        ["info"],
        ["convert"],
        ["reconstruct"],
        ["evaluate"],
        ["bench"],
        ["data", "prepare"],
        ["live"],
        ["send"],
        ["rig", "suggest"],
        ["compare"],
        ["gui"],
    ],
)
def test_every_command_that_reads_bvh_takes_a_rig_map(command, capsys):
    from engine.cli.main import build_parser

    with pytest.raises(SystemExit):
        build_parser().parse_args([*command, "--help"])
    assert "--rig-map MAP.toml" in capsys.readouterr().out
