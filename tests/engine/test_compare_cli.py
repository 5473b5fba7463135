"""`dragposer-studio compare`: passes cached as JSON, the document rebuilt from the cache."""

from __future__ import annotations

import json

import pytest

from engine.cli import compare, comparison_doc
from engine.cli.main import main


def test_compare_writes_the_document_and_reuses_its_cache(tmp_path, synthetic_motion, monkeypatch, capsys):
    bvh = pytest.importorskip("engine.motion.bvh")
    bvh.save_motion_bvh(tmp_path / "walk.bvh", synthetic_motion)
    passes = (
        ("6", False, ("ik",)),
        ("6", True, ("ik",)),
        ("3-head-hands", False, ("ik",)),
        ("3-head-hands", True, ("ik",)),
    )
    monkeypatch.setattr(compare, "PASSES", passes)
    monkeypatch.setattr(comparison_doc, "PASSES", passes)
    out, cache = tmp_path / "comparison.md", tmp_path / "cache"
    args = [
        "compare",
        str(tmp_path / "walk.bvh"),
        "--out",
        str(out),
        "--cache",
        str(cache),
        "--no-progress",
        "--max-frames",
        "100",
        "--passes",
        "1,4",
    ]
    assert main(args) == 0
    assert sorted(p.name for p in cache.iterdir()) == ["3-head-hands-gaps-ik.json", "6-ik.json"]
    doc = json.loads((cache / "6-ik.json").read_text())
    assert doc["total"]["frames"] == 100 and doc["variant"] == "ik" and doc["max_frames"] == 100
    text = out.read_text()
    assert "## 1. Preset `6`" in text and "| ik |" in text and "(not run yet)" in text and "--max-frames 100" in text
    assert "HUMAN4D" in text and "RPM smooth" in text  # the papers' figures beside ours
    (cache / "6-ik.json").write_text(json.dumps({**doc, "total": {**doc["total"], "pos_cm": 123.0}}))
    assert main([*args, "--table-only"]) == 0
    assert "| ik | 123.00 |" in out.read_text(), "the table comes from the cache"
    assert main([*args[:-2], "--passes", "7"]) == 2
    assert "numbered 1-4" in capsys.readouterr().err


def test_targets_say_what_is_met_and_what_auj_measures():
    def row(**t):
        return {"total": {"ms_per_frame": 9.0, "gt_jitter": 13.0, "gt_jerk": 30.0, **t}}

    res = {
        ("6", False, "dragposer"): row(pos_cm=1.6),
        ("6", False, "sparseposer"): row(pos_cm=2.4),
        ("3-head-hands", True, "dragposer"): row(pj=90.0, auj=1000.0, auj_raw=1200.0, gt_pj=9.0, gt_auj=99.0),
        ("3-head-hands", True, "dragposer+blend"): row(pj=50.0, auj=400.0, auj_raw=900.0),
        ("3-head-hands", True, "rpm"): row(pj=40.0, auj=700.0),
    }
    text = "\n".join(comparison_doc._targets(res, 0.5))
    assert "2.40 cm against DragPoser's 1.60 cm on the same frames (1.50x; target <= 1.25x): **not met**" in text
    assert "PJ 40.0 / AUJ 700 against DragPoser's 90.0 / 1000 without smoothing: **met**" in text
    assert "400 against 1000 without (0.40x; target <= 0.5x): **met**" in text
    assert (
        "ground truth's mean jerk (30.0 here)" in text
        and "PJ 9.0 / AUJ 99." in text
        and "900 against 1200 (0.75x)" in text
    )


def test_a_cached_gap_pass_from_before_flowmdms_jerk_is_run_again(tmp_path):
    f = tmp_path / "x.json"
    f.write_text(json.dumps({"total": {"pj": 1.0, "auj": 2.0}}))
    assert not compare._cached(f, gaps=True) and compare._cached(f, gaps=False)
    f.write_text(json.dumps({"total": {"pj": 1.0, "auj": 2.0, "pj_raw": 3.0}}))
    assert compare._cached(f, gaps=True) and not compare._cached(tmp_path / "missing.json", gaps=False)
