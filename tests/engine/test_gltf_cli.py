"""The commands write glTF when ``--out`` ends in .glb or .gltf (docs/export.md), refuse an
extension no writer knows before any work, and add comparison characters and trackers."""

from __future__ import annotations

import numpy as np
import pytest

from engine.cli.main import main
from engine.motion.bvh import load_bvh, save_motion_bvh
from tests.engine.gltf_reading import Y_UP_TO_Z_UP, bvh_world_positions, read_gltf, validate, validator_command
from tests.engine.test_reconstruct import standin_dragposer  # noqa: F401  (fixture)


@pytest.fixture
def clip_path(synthetic_motion, tmp_path):
    path = tmp_path / "walk.bvh"
    save_motion_bvh(path, synthetic_motion)
    return path


def _positions(path, names, frames):
    read = read_gltf(path)
    nodes = [read.node_index(n) for n in names]
    return read.world_positions(nodes, frames) @ Y_UP_TO_Z_UP.T


def test_convert_writes_the_same_motion_as_glb_and_bvh(clip_path, tmp_path):
    assert main(["convert", str(clip_path), "--out", str(tmp_path / "c.bvh")]) == 0
    assert main(["convert", str(clip_path), "--out", str(tmp_path / "c.glb")]) == 0
    assert (tmp_path / "c.glb").read_bytes()[:4] == b"glTF"
    raw = load_bvh(tmp_path / "c.bvh")
    got = _positions(tmp_path / "c.glb", list(raw.names), raw.frames)
    assert np.abs(got - bvh_world_positions(raw)).max() < 1e-5
    if validator_command() is not None:
        assert [(r["errors"], r["warnings"]) for r in validate([tmp_path / "c.glb"])] == [(0, 0)]


def test_reconstruct_adds_ghosts_and_tracker_nodes(standin_dragposer, clip_path, tmp_path, capsys):  # noqa: F811
    out = tmp_path / "r.glb"
    assert (
        main(
            [
                "reconstruct",
                str(clip_path),
                "--out",
                str(out),
                "--iterations",
                "2",
                "--max-frames",
                "12",
                "--ghosts",
                "ik",
                "--tracker-nodes",
                "--on-source-rig",
                "--no-progress",
            ]
        )
        == 0
    )
    assert "wrote" in capsys.readouterr().out
    doc = read_gltf(out).doc
    names = [n.name for n in doc.nodes]
    assert len(doc.skins) == 2 and "ik:lwrist" in names and "lwrist" in names
    trackers = [n for n in names if n.startswith("tracker:")]
    assert len(trackers) == 6 and {"tracker:root", "tracker:lwrist", "tracker:upperneck"} <= set(trackers)
    assert len(doc.meshes) == 3  # two bodies and the trackers' box
    times = read_gltf(out).channels()[(names.index("root"), "rotation")][0]
    assert len(times) == 12
    assert (
        main(
            [
                "reconstruct",
                str(clip_path),
                "--out",
                str(tmp_path / "n.gltf"),
                "--iterations",
                "2",
                "--max-frames",
                "6",
                "--no-mesh",
                "--no-progress",
            ]
        )
        == 0
    )
    assert not read_gltf(tmp_path / "n.gltf").doc.meshes
    if validator_command() is not None:
        for r in validate([out, tmp_path / "n.gltf"]):
            assert (r["errors"], r["warnings"]) == (0, 0), r


def test_out_dir_takes_the_out_format(standin_dragposer, clip_path, tmp_path):  # noqa: F811
    assert (
        main(
            [
                "reconstruct",
                str(clip_path),
                "--out-dir",
                str(tmp_path / "d"),
                "--out-format",
                "glb",
                "--iterations",
                "1",
                "--max-frames",
                "4",
                "--no-progress",
            ]
        )
        == 0
    )
    assert [p.name for p in (tmp_path / "d").iterdir()] == ["walk.glb"]


@pytest.mark.parametrize(
    "flags, message",
    [
        (["--out", "{tmp}/o.txt"], "'.txt' is not a motion format this program writes; known: .bvh"),
        (["--out", "{tmp}/o.bvh", "--no-mesh"], "--no-mesh applies to glTF output"),
        (["--out", "{tmp}/o.bvh", "--ghosts", "ik", "--tracker-nodes"], "--tracker-nodes and --ghosts apply"),
        (["--out", "{tmp}/o.glb", "--ghosts", "nosuch"], "--ghosts: unknown method 'nosuch'; available:"),
    ],
)
def test_reconstruct_refuses_bad_outputs_before_any_work(
    standin_dragposer,  # noqa: F811
    clip_path,
    tmp_path,
    capsys,  # noqa: F811
    flags,
    message,
):
    flags = [f.replace("{tmp}", str(tmp_path)) for f in flags]
    assert main(["reconstruct", str(clip_path), *flags, "--no-progress"]) == 2
    assert message in capsys.readouterr().err
    assert not standin_dragposer, "no method was built"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["walk.bvh"]


def test_recordings_take_no_ghosts_and_bake_checks_the_extension_first(tmp_path, capsys):
    rec = tmp_path / "r.jsonl"
    rec.write_text("")
    assert main(["reconstruct", "--trackers", str(rec), "--out", str(tmp_path / "o.glb"), "--ghosts", "ik"]) == 2
    assert "apply to IN.bvh reconstructions" in capsys.readouterr().err
    scene = tmp_path / "s.json"
    scene.write_text("{}")
    assert main(["bake", str(scene), "--out", str(tmp_path / "o.fbx"), "--no-progress"]) == 2
    assert "known: .bvh (BVH motion), .glb (glTF 2.0 binary), .gltf (glTF 2.0 JSON)" in capsys.readouterr().err


def test_out_dir_with_a_glb_only_option_asks_for_the_out_format(clip_path, tmp_path, capsys):
    assert main(["reconstruct", str(clip_path), "--out-dir", str(tmp_path / "d"), "--no-mesh", "--no-progress"]) == 2
    assert "--no-mesh applies to glTF output: add --out-format glb or gltf" in capsys.readouterr().err


def test_on_the_source_rig_at_another_rate_the_glb_matches_the_bvh(standin_dragposer, clip_path, tmp_path):  # noqa: F811
    common = ["--iterations", "1", "--max-frames", "20", "--on-source-rig", "--fps", "30", "--no-progress"]
    assert main(["reconstruct", str(clip_path), "--out", str(tmp_path / "r.bvh"), *common]) == 0
    assert main(["reconstruct", str(clip_path), "--out", str(tmp_path / "r.glb"), *common]) == 0
    raw = load_bvh(tmp_path / "r.bvh")
    assert raw.frames == 10
    got = _positions(tmp_path / "r.glb", list(raw.names), raw.frames)
    assert np.abs(got - bvh_world_positions(raw)).max() < 1e-5
