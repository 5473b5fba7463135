"""``bench`` times a method on a clip and reports it (speed is reported, not asserted)."""

from __future__ import annotations

import json

from engine.bvh import save_motion_bvh
from engine.cli.main import main


def test_bench_ik_writes_a_report(synthetic_motion, tmp_path, capsys):
    clip = tmp_path / "clip.bvh"
    save_motion_bvh(clip, synthetic_motion)
    out = tmp_path / "bench.json"
    assert main(["bench", str(clip), "--method", "ik", "--frames", "20", "--warmup", "2", "--json", str(out)]) == 0
    data = json.loads(out.read_text())
    (row,) = data["methods"]
    assert row["method"] == "ik" and row["frames"] == 20
    assert 0 < row["ms_median"] <= row["ms_p95"]
    assert data["machine"]["cpu_count"] >= 1
    assert "ik" in capsys.readouterr().out


def test_bench_unknown_method_is_a_user_error(synthetic_motion, tmp_path, capsys):
    clip = tmp_path / "clip.bvh"
    save_motion_bvh(clip, synthetic_motion)
    assert main(["bench", str(clip), "--method", "nope", "--frames", "5"]) == 2
    assert "unknown method" in capsys.readouterr().err
