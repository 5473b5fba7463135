"""``bench`` times a method on a clip and reports it (speed is reported, not asserted)."""

from __future__ import annotations

import json

from engine.cli.main import main
from engine.motion.bvh import save_motion_bvh


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


def test_bench_scene_solves_its_constraints_and_reports_the_same_keys(synthetic_motion, tmp_path, capsys, monkeypatch):
    from pathlib import Path

    from engine.methods import driver

    clip = tmp_path / "clip.bvh"
    save_motion_bvh(clip, synthetic_motion)
    scene = Path(__file__).resolve().parents[2] / "assets" / "scenes" / "look_floor_pin_distance.json"
    given = []
    real = driver.set_constraints
    monkeypatch.setattr(driver, "set_constraints", lambda m, cs: given.append([c.kind for c in cs]) or real(m, cs))
    rows = []
    for extra in ([], ["--scene", str(scene)]):
        out = tmp_path / f"bench{len(extra)}.json"
        args = ["bench", str(clip), "--method", "dragposer", "--frames", "4", "--warmup", "1", "--iterations", "2"]
        assert main([*args, "--json", str(out), *extra]) == 0
        rows.append(json.loads(out.read_text()))
    assert given == [["look_at", "floor", "pin", "distance"]]
    assert rows[0]["methods"][0].keys() == rows[1]["methods"][0].keys() and rows[1]["scene"] == str(scene)
    assert "4 constraints" in capsys.readouterr().out
    assert main(["bench", str(clip), "--method", "ik", "--frames", "2", "--warmup", "1", "--scene", str(scene)]) == 2
    assert "takes no constraints" in capsys.readouterr().err


def test_bench_offline_times_the_batched_solve_and_reports_the_same_keys(synthetic_motion, tmp_path, monkeypatch):
    from engine.methods import dragposer_batch

    clip = tmp_path / "clip.bvh"
    save_motion_bvh(clip, synthetic_motion)
    calls = []
    real = dragposer_batch.solve_clip
    monkeypatch.setattr(dragposer_batch, "solve_clip", lambda m, frames: calls.append(len(frames)) or real(m, frames))
    rows = []
    for mode in ("realtime", "offline"):
        out = tmp_path / f"{mode}.json"
        args = ["bench", str(clip), "--method", "dragposer", "--frames", "6", "--warmup", "2", "--mode", mode]
        assert main([*args, "--json", str(out)]) == 0
        rows.append(json.loads(out.read_text())["methods"][0])
    assert calls == [8]  # the offline run solved its 2 + 6 frames in one call
    assert rows[0].keys() == rows[1].keys()
    assert rows[1]["frames"] == 6 and rows[1]["iterations_mean"] >= 1 and rows[1]["ms_per_iteration_median"] > 0
