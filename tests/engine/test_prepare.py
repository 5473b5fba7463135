"""``data prepare`` and ``info`` on a small copy of the shared data."""

from __future__ import annotations

import json
import shutil

import numpy as np
import pytest

from engine.cli.main import main
from engine.data.prepare import assign_splits, prepare

FILES = [
    "cmu_iclone/007_02.bvh",
    "cmu_iclone/007_03.bvh",
    "cmu_iclone/002_03.bvh",
    "cmu_daz/salsa/07.bvh",
    "dragposer/example_3.bvh",
]


@pytest.fixture(scope="module")
def small_corpus(shared_mocap, tmp_path_factory):
    root = tmp_path_factory.mktemp("corpus")
    for rel in FILES:
        (root / rel).parent.mkdir(parents=True, exist_ok=True)
        shutil.copy(shared_mocap / rel, root / rel)
    shutil.copy(shared_mocap / "manifest.json", root / "manifest.json")  # true fps for salsa
    (root / "cmu_iclone/broken.bvh").write_text("HIERARCHY\nROOT Hips\n{\n OFFSET 0 0\n")
    return root


def test_split_rule_is_deterministic_and_keeps_eval_only_out():
    rels = [f"mocap/cmu_iclone/{i:03d}.bvh" for i in range(20)] + ["mocap/dragposer/a.bvh"]
    s1, s2 = assign_splits(rels, ["dragposer/*"]), assign_splits(list(reversed(rels)), ["dragposer/*"])
    assert s1 == s2
    assert s1["mocap/dragposer/a.bvh"] == "test"
    assert [r for r in rels if s1[r] == "val"] == [
        "mocap/cmu_iclone/003.bvh",
        "mocap/cmu_iclone/011.bvh",
        "mocap/cmu_iclone/019.bvh",
    ]


def test_prepare_writes_shards_stats_and_reports_failures(small_corpus, tmp_path):
    out = tmp_path / "prep"
    res = prepare([small_corpus], out, progress=False)
    assert [p for p, _ in res.failed] == [str((small_corpus / "cmu_iclone/broken.bvh").resolve())]
    assert "broken.bvh" in res.failed[0][0] and res.failed[0][1]
    man = json.loads((out / "manifest.json").read_text())
    by = {(e["source"], e["mirrored"]): e for e in man["files"]}
    assert by[("dragposer/example_3.bvh", False)]["split"] == "test"
    assert ("dragposer/example_3.bvh", True) not in by, "eval-only clips are not mirrored"
    assert ("cmu_iclone/007_02.bvh", True) in by
    salsa = by[("cmu_daz/salsa/07.bvh", False)]
    assert salsa["source_fps"] == 60.0, "true fps must come from the manifest, not the header"
    for e in man["files"]:
        d = np.load(out / e["shard"])
        assert d["local_rot"].shape == (e["frames"], 22, 4) and d["root_pos"].shape == (e["frames"], 3)
        assert d["offsets"].shape == (22, 3)
    st = man["stats"]
    assert np.array(st["dq_mean"]).shape == (22, 8) and np.array(st["disp_std"]).shape == (3,)
    assert min(np.array(st["dq_std"]).ravel()) > 0
    # mirrored copy: left and right swapped, x negated
    a = np.load(out / by[("cmu_iclone/007_02.bvh", False)]["shard"])
    b = np.load(out / by[("cmu_iclone/007_02.bvh", True)]["shard"])
    np.testing.assert_allclose(b["root_pos"][:, 0], -a["root_pos"][:, 0], atol=1e-6)

    before = {p.name: p.stat().st_mtime_ns for p in out.rglob("*") if p.is_file()}
    again = prepare([small_corpus], out, progress=False)
    assert again.unchanged and again.written == 0 and again.reused == len(man["files"])
    after = {p.name: p.stat().st_mtime_ns for p in out.rglob("*") if p.is_file()}
    assert before == after, "a re-run with unchanged inputs must not rewrite anything"


def test_info_json_on_each_rig(shared_mocap, capsys):
    for rel, rig, fps in [
        ("cmu_daz/salsa/01.bvh", "cmu_daz", 60.0),
        ("cmu_iclone/002_01.bvh", "cmu_iclone", 60.0),
        ("dragposer/example_2.bvh", "dragposer", 120.0),
    ]:
        assert main(["info", str(shared_mocap / rel), "--json"]) == 0
        out = json.loads(capsys.readouterr().out)
        assert set(out) >= {
            "rig",
            "source_joints",
            "source_frames",
            "source_fps",
            "frames",
            "fps",
            "joints",
            "height_m",
        }
        assert out["rig"] == rig and out["source_fps"] == fps and out["fps"] == 60 and out["joints"] == 22
        assert 1.4 < out["height_m"] < 2.4


def test_info_fps_override_and_errors(shared_mocap, tmp_path, capsys):
    assert main(["info", str(shared_mocap / "cmu_daz/salsa/01.bvh"), "--fps", "120", "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["source_fps"] == 120
    bad = tmp_path / "bad.bvh"
    bad.write_text(
        "HIERARCHY\nROOT Hips\n{\n  OFFSET 0 0 0\n  CHANNELS 6 Xposition Yposition Zposition "
        "Zrotation Xrotation Yrotation\n}\nMOTION\nFrames: 1\nFrame Time: 0.1\n0 0 0 0 0 0\n"
    )
    assert main(["info", str(bad)]) == 2
    err = capsys.readouterr().err
    assert "bad.bvh" in err and "cannot map this skeleton" in err and "Traceback" not in err


# Every shared file loading as a finite clip: test_retarget_shared.py, whose sweep loads
# each file once for its height and rotation checks too.


def test_data_list_prints_the_split(small_corpus, tmp_path, capsys):
    out = tmp_path / "prep"
    prepare([small_corpus], out, progress=False)
    assert main(["data", "list", "--data", str(out), "--split", "test"]) == 0
    lines = capsys.readouterr().out.split()
    assert lines == [str((small_corpus / "dragposer/example_3.bvh").resolve())]
