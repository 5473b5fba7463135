"""`dragposer-studio compare`: passes cached as JSON, the document rebuilt from the cache."""

from __future__ import annotations

import json

import pytest

from engine.cli import compare, comparison_doc
from engine.cli.main import main


def test_compare_writes_the_document_and_reuses_its_cache(tmp_path, synthetic_motion, monkeypatch, capsys):
    bvh = pytest.importorskip("engine.bvh")
    bvh.save_motion_bvh(tmp_path / "walk.bvh", synthetic_motion)
    passes = (("6", False, ("ik",)), ("6", True, ("ik",)), ("3-head-hands", False, ("ik",)),
              ("3-head-hands", True, ("ik",)))  # fmt: skip
    monkeypatch.setattr(compare, "PASSES", passes)
    monkeypatch.setattr(comparison_doc, "PASSES", passes)
    out, cache = tmp_path / "comparison.md", tmp_path / "cache"
    args = ["compare", str(tmp_path / "walk.bvh"), "--out", str(out), "--cache", str(cache), "--no-progress",
            "--max-frames", "100", "--passes", "1,4"]
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
