"""``data prepare`` on every shared folder: copies of one take share a split, today's
validation takes stay in validation, rest frames are dropped."""

from __future__ import annotations

import shutil

import pytest

#: The validation files of the split the shipped models were trained with (model card).
TODAYS_VAL = [
    "cmu_daz/indian/14.bvh",
    "cmu_daz/salsa/07.bvh",
    "cmu_iclone/002_01.bvh",
    "cmu_iclone/002_09.bvh",
    "cmu_iclone/005_05.bvh",
    "cmu_iclone/005_13.bvh",
    "cmu_iclone/006_02.bvh",
    "cmu_iclone/006_10.bvh",
    "cmu_iclone/007_05.bvh",
]


@pytest.mark.shared_data
def test_every_copy_of_a_shared_take_lands_in_one_split_and_todays_validation_stays(shared_mocap):
    from engine.data.prepare import EVAL_ONLY, discover, split_files

    files = discover([shared_mocap])
    split, takes = split_files(files, list(EVAL_ONLY))
    by_take: dict[str, set] = {}
    for rel, take in takes.items():
        if take:
            by_take.setdefault(take, set()).add(split[rel])
    assert all(len(s) == 1 for s in by_take.values()), {t: s for t, s in by_take.items() if len(s) > 1}
    assert len({t for rel, t in takes.items() if rel.endswith(".bvh")}) == 110
    # adding the ASF/AMC folders moves no BVH take between train and validation
    bvh_only, _ = split_files([f for f in files if f[1].endswith(".bvh")], ["dragposer/*"])
    assert {rel: split[rel] for rel in bvh_only} == bvh_only
    assert {s for rel, s in split.items() if rel.startswith(("hdm05/", "dragposer/"))} == {"test"}
    assert {s for rel, s in split.items() if rel.startswith("cmu_asf/105/")} == {"train", "val"}
    assert all(split[rel] == "val" for rel in TODAYS_VAL)
    assert {rel.split("/")[0] for rel, s in split.items() if s == "train"} >= {"cmu_mb", "cmu_daz_cgspeed"}


@pytest.mark.shared_data
def test_prepare_drops_the_rest_frame_and_uses_the_true_rate(shared_mocap, tmp_path):
    import json

    from engine.data.prepare import prepare

    root = tmp_path / "mocap"
    for rel in ("cmu_mb/07_03.bvh", "cmu_daz_cgspeed/07_03.bvh", "cmu_iclone/007_03.bvh"):
        (root / rel).parent.mkdir(parents=True, exist_ok=True)
        shutil.copy(shared_mocap / rel, root / rel)
    shutil.copy(shared_mocap / "manifest.json", root / "manifest.json")
    prepare([root], tmp_path / "prep", progress=False, mirror=False)
    man = json.loads((tmp_path / "prep" / "manifest.json").read_text())
    by = {e["source"]: e for e in man["files"]}
    assert {e["take"] for e in by.values()} == {"007_03"} and len({e["split"] for e in by.values()}) == 1
    assert by["cmu_mb/07_03.bvh"]["source_fps"] == 120.0 and by["cmu_iclone/007_03.bvh"]["source_fps"] == 60.0
    # 416 frames at 120 fps less the rest frame: 415 -> 208 at 60 fps (with it, the first would be the rest pose)
    assert by["cmu_mb/07_03.bvh"]["frames"] == 208 and by["cmu_mb/07_03.bvh"]["skipped"] == 1
    assert by["cmu_daz_cgspeed/07_03.bvh"]["skipped"] == 10
