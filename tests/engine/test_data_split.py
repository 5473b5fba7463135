"""The train/validation split of ``data prepare``: by take, about one take in 8 in
validation, reference folders keep their validation files, copies never straddle it."""

from __future__ import annotations

import json
import shutil

import pytest

from engine.data.prepare import assign_splits, discover, prepare, split_files


def test_a_take_follows_its_copy_in_the_reference_folder():
    rels = [f"a/{i:02d}.bvh" for i in range(8)] + [f"b/{i:02d}.bvh" for i in range(8)]
    # a/03 is validation by a's folder rule, a/05 training; their copies b/05 and b/03 follow them
    # whatever b's own folder rule says (b/03 would be validation there).
    takes = {"a/03.bvh": "t3", "b/05.bvh": "t3", "a/05.bvh": "t5", "b/03.bvh": "t5"}
    split = assign_splits(rels, [], takes, reference=("a",))
    assert split["a/03.bvh"] == split["b/05.bvh"] == "val"
    assert split["a/05.bvh"] == split["b/03.bvh"] == "train"
    # files naming no take keep their folder rule: only b/03 (now a copy of t5) would have been val in b
    assert [r for r in rels if r.startswith("b/") and split[r] == "val"] == ["b/05.bvh"]


def test_takes_only_on_other_folders_are_split_by_sorted_take_key():
    rels, takes = [], {}
    for i in range(16):
        for folder in ("b", "c"):
            rel = f"{folder}/{15 - i:02d}.bvh"  # file order opposite to take order
            rels.append(rel)
            takes[rel] = f"take{i:02d}"
    split = assign_splits(rels, [], takes, reference=("a",))
    val_takes = sorted({takes[r] for r in rels if split[r] == "val"})
    assert val_takes == ["take03", "take11"]
    for i in range(16):
        assert split[f"b/{15 - i:02d}.bvh"] == split[f"c/{15 - i:02d}.bvh"]
    assert split == assign_splits(list(reversed(rels)), [], takes, reference=("a",))


@pytest.mark.shared_data
def test_about_one_take_in_eight_is_validation_on_the_shared_data(shared_mocap):
    split, takes = split_files(discover([shared_mocap]), ["dragposer/*"])
    units: dict[str, set] = {}
    for rel, s in split.items():
        if s != "test":
            units.setdefault(takes.get(rel) or rel, set()).add(s)
    assert all(len(s) == 1 for s in units.values())
    n_val = sum(s == {"val"} for s in units.values())
    assert 1 / 10 < n_val / len(units) < 1 / 7, (n_val, len(units))
    files_val = sum(s == "val" for s in split.values())
    assert files_val / sum(s != "test" for s in split.values()) < 0.15
    # takes recorded only on the newer rigs reach validation too
    assert {rel.split("/")[0] for rel, s in split.items() if s == "val"} >= {"cmu_mb", "cmu_daz_cgspeed"}


@pytest.mark.shared_data
def test_reused_shards_take_the_current_split_and_the_hash_follows_it(shared_mocap, tmp_path, monkeypatch):
    import engine.data.prepare as prep

    root = tmp_path / "mocap"
    (root / "cmu_iclone").mkdir(parents=True)
    for name in ("007_02.bvh", "007_03.bvh"):
        shutil.copy(shared_mocap / "cmu_iclone" / name, root / "cmu_iclone" / name)
    out = tmp_path / "prep"
    prepare([root], out, progress=False, mirror=False)
    man_path = out / "manifest.json"
    first = json.loads(man_path.read_text())
    assert [e["split"] for e in first["files"]] == ["train", "train"]
    # a manifest written under another split rule: same shards, other split
    stale = dict(first, files=[dict(e, split="val") for e in first["files"]], hash="0")
    man_path.write_text(json.dumps(stale))
    res = prepare([root], out, progress=False, mirror=False)
    again = json.loads(man_path.read_text())
    assert res.reused == 2 and res.written == 0
    assert [e["split"] for e in again["files"]] == ["train", "train"] and again["hash"] == first["hash"]
    # the same shards with another split are other training data: another hash
    monkeypatch.setattr(
        prep, "assign_splits", lambda rels, *a, **k: {r: "val" if r.endswith("007_02.bvh") else "train" for r in rels}
    )
    prepare([root], out, progress=False, mirror=False)
    assert json.loads(man_path.read_text())["hash"] != first["hash"]
