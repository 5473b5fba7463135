"""`dragposer-studio evaluate` end to end on a synthetic clip written as BVH."""

from __future__ import annotations

import json

import numpy as np
import pytest

from engine.cli.evaluate import evaluate_clip, find_clips
from engine.cli.main import main
from engine.methods import get_method

METRIC_KEYS = {
    "frames",
    "pos_cm",
    "rot_deg",
    "vel_cms",
    "ee_cm",
    "jitter",
    "gt_jitter",
    "iterations_mean",
    "ms_per_frame",
}


def test_evaluate_clip_without_files(synthetic_motion):
    m = evaluate_clip(synthetic_motion, get_method("ik"), "6", progress=False)
    assert METRIC_KEYS <= set(m) and "pj" not in m
    assert m["frames"] == 120 and m["ee_cm"] < 2.0 and m["iterations_mean"] == 0.0
    lossy = evaluate_clip(synthetic_motion, get_method("ik"), "4", faulty=0.05, seed=1, progress=False)
    assert {"pj", "auj", "pj_ts", "auj_st"} <= set(lossy)
    assert "latent_step" not in m, "IK has no latent"


def test_latent_methods_report_their_latent_step(synthetic_motion):
    import torch

    from engine.methods.dragposer import DragPoserMethod
    from tests.engine.test_optimizer_standins import MLPDecoder

    torch.manual_seed(0)
    m = evaluate_clip(synthetic_motion.slice(0, 20), DragPoserMethod(MLPDecoder(), iterations=2), "6", progress=False)
    assert m["latent_step"] > 0 and np.isfinite(m["latent_step"])


@pytest.fixture
def clip_dir(tmp_path, synthetic_motion):
    bvh = pytest.importorskip("engine.motion.bvh")
    pytest.importorskip("engine.motion.retarget")
    sub = tmp_path / "clips" / "nested"
    sub.mkdir(parents=True)
    bvh.save_motion_bvh(sub / "walk.bvh", synthetic_motion)
    bvh.save_motion_bvh(tmp_path / "clips" / "short.BVH", synthetic_motion.slice(0, 80))
    (tmp_path / "clips" / "notes.txt").write_text("not a clip")
    return tmp_path / "clips"


def test_cli_writes_table_and_json(clip_dir, tmp_path, capsys):
    out = tmp_path / "res" / "eval.json"
    code = main(
        [
            "evaluate",
            str(clip_dir),
            "--method",
            "ik",
            "--sensors",
            "6",
            "--gaps",
            "--mode",
            "offline",
            "--iterations",
            "3",
            "--max-frames",
            "100",
            "--seed",
            "2",
            "--json",
            str(out),
            "--no-progress",
        ]
    )
    assert code == 0
    text = capsys.readouterr().out
    assert "walk.bvh" in text and "short.BVH" in text and "total" in text and "PJ" in text
    doc = json.loads(out.read_text())
    assert doc["method"] == "ik" and doc["preset"] == "6" and doc["mode"] == "offline"
    assert len(doc["files"]) == 2
    for m in [doc["total"], *doc["files"].values()]:
        assert METRIC_KEYS | {"pj", "auj"} <= set(m)
    frames = {k.rsplit("/", 1)[-1]: v["frames"] for k, v in doc["files"].items()}
    assert frames == {"walk.bvh": 100, "short.BVH": 80}
    assert doc["total"]["frames"] == 180
    files = list(doc["files"].values())
    weighted = sum(f["pos_cm"] * f["frames"] for f in files) / sum(f["frames"] for f in files)
    assert doc["total"]["pos_cm"] == pytest.approx(weighted)
    assert not list(out.parent.glob(".*tmp"))  # no temporary file left behind


def test_cli_matches_the_function_underneath(clip_dir, tmp_path):
    from engine.motion.retarget import load_motion

    out = tmp_path / "e.json"
    walk = next(clip_dir.rglob("walk.bvh"))
    assert main(["evaluate", str(walk), "--sensors", "4", "--json", str(out), "--no-progress"]) == 0
    doc = json.loads(out.read_text())
    ref = evaluate_clip(load_motion(walk), get_method("ik"), "4", progress=False)
    got = doc["files"][str(walk)]
    for k in ("pos_cm", "rot_deg", "ee_cm", "jitter"):
        assert got[k] == pytest.approx(ref[k], rel=1e-9)


@pytest.mark.parametrize(
    "argv, message",
    [
        (["--method", "nope"], "unknown method"),
        (["--sensors", "7"], "valid presets"),
        (["--faulty", "2"], "--faulty"),
        (["--set", "lr=0.1"], "no optimizer settings"),
        (["--method", "dragposer", "--predictor", "p.pt"], "needs the VAE"),
        (["--method", "autoencoder", "--vae", "missing.pt"], "missing.pt"),
        (["--set", "warp=9"], "--set warp: unknown setting"),
        (["--set", "iterations=many"], "--set iterations=many: not a valid int"),
    ],
)
def test_cli_user_errors(clip_dir, capsys, argv, message):
    assert main(["evaluate", str(clip_dir), "--no-progress", *argv]) == 2
    assert message in capsys.readouterr().err


def test_a_bad_setting_fails_before_any_worker_starts(clip_dir, capsys, monkeypatch):
    import engine.cli.evaluate as ev

    monkeypatch.setattr(ev, "map_files", lambda *a, **k: pytest.fail("the workers started"))
    assert main(["evaluate", str(clip_dir), "--no-progress", "--jobs", "2", "--set", "warp=9"]) == 2
    assert "--set warp: unknown setting" in capsys.readouterr().err


def test_missing_path_is_a_user_error(tmp_path, capsys):
    assert main(["evaluate", str(tmp_path / "missing.bvh")]) == 2
    assert "no such file" in capsys.readouterr().err
    (tmp_path / "empty").mkdir()
    assert main(["evaluate", str(tmp_path / "empty")]) == 2


def test_find_clips_recurses_and_dedups(clip_dir):
    files = find_clips([clip_dir, next(clip_dir.rglob("walk.bvh"))])
    assert sorted(f.name for f in files) == ["short.BVH", "walk.bvh"]
    assert np.unique([str(f) for f in files]).size == 2


def test_set_reaches_the_method(monkeypatch):
    from engine.cli.method_options import apply_settings

    seen = {}

    class Configurable:
        def configure(self, **values):
            seen.update(values)

    assert apply_settings(Configurable(), "x", ["optimizer=sgd", "lr=0.3", "root_anchor=none"]) == seen
    assert seen == {"optimizer": "sgd", "lr": 0.3, "root_anchor": "none"}
    assert apply_settings(object(), "ik", []) == {}


def test_several_methods_in_one_pass(clip_dir, tmp_path, capsys):
    import torch

    from engine.models.loading import FORMAT_VERSION
    from engine.models.rpm import RPM, RPMConfig
    from engine.models.sparseposer import SparsePoser, SparsePoserConfig

    torch.manual_seed(0)
    weights, sp_weights = tmp_path / "rpm.pt", tmp_path / "sp.pt"
    for path, kind, model in (
        (weights, "rpm", RPM(RPMConfig(past_inputs=2, past_poses=2, window=3, hidden=16, blocks=1))),
        (sp_weights, "sparseposer", SparsePoser(SparsePoserConfig(window=8, channels=(4, 4, 4)))),
    ):
        torch.save(
            {
                "format_version": FORMAT_VERSION,
                "kind": kind,
                "config": model.config.to_dict(),
                "state_dict": model.state_dict(),
                "meta": {},
            },
            path,
        )
    walk = next(clip_dir.rglob("walk.bvh"))
    out, md = tmp_path / "multi.json", tmp_path / "table.md"
    args = [
        "evaluate",
        str(walk),
        "--sensors",
        "3-head-hands",
        "--gaps",
        "--max-frames",
        "90",
        "--no-progress",
        "--rpm-model",
        str(weights),
        "--sparseposer-model",
        str(sp_weights),
        "--json",
        str(out),
        "--markdown",
        str(md),
    ]
    assert main([*args, "--method", "ik,rpm,sparseposer"]) == 0
    text = capsys.readouterr().out
    assert text.splitlines()[0].startswith("method") and "sparseposer: not evaluated" in text and "'6'" in text
    doc = json.loads(out.read_text())
    assert set(doc) == {"ik", "rpm", "sparseposer"} and "error" in doc["sparseposer"]
    single = tmp_path / "ik.json"
    assert main([*args[:-6], "--method", "ik", "--json", str(single)]) == 0
    assert doc["ik"]["total"] == json.loads(single.read_text())["total"] | {
        "ms_per_frame": doc["ik"]["total"]["ms_per_frame"]
    }
    assert {"pj", "auj"} <= set(doc["rpm"]["total"]) and doc["rpm"]["files"]
    lines = md.read_text().splitlines()
    assert lines[0].startswith("| method |") and "PJ" in lines[0] and len(lines) == 5
    capsys.readouterr()
    assert main([*args, "--method", "ik,ik"]) != 0
    assert "named twice" in capsys.readouterr().err
