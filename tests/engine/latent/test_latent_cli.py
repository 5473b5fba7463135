"""``dragposer-studio latent``: a headless report of a real clip, and its refusals."""

from __future__ import annotations

import json

import numpy as np
import pytest

from engine.cli.main import main


def test_report_of_a_shared_clip(shared_mocap, tmp_path, capsys):
    clip = shared_mocap / "cmu_iclone" / "002_09.bvh"  # a validation file the models never saw
    out, js = tmp_path / "report.png", tmp_path / "report.json"
    code = main(
        [
            "latent",
            str(clip),
            "--sensors",
            "4",
            "--scene",
            "assets/scenes/look_floor_pin_distance.json",
            "--out",
            str(out),
            "--json",
            str(js),
            "--max-frames",
            "24",
            "--no-progress",
        ]
    )
    assert code == 0
    from matplotlib.image import imread

    img = imread(out)
    assert img.shape[:2] == (700, 1200)
    assert img[..., :3].std() > 0.05  # drawn, not blank
    doc = json.loads(js.read_text())
    frames = doc["frames"]
    assert [f["frame"] for f in frames] == list(range(24))
    assert {"x", "y", "nearest", "norm", "predictor", "flagged", "start", "pos_cm", "iterations"} <= set(frames[0])
    assert frames[0]["start"] in ("zero latent", "pose bank", "predictor")
    assert all(f["start"] in ("previous frame", "pose bank", "predictor") for f in frames[1:])
    assert all(0 < f["nearest"] < 10 and 0 < f["norm"] < 20 and f["pos_cm"] > 0 for f in frames)
    s = doc["summary"]
    assert s["frames"] == 24 and s["flagged"] == [f["frame"] for f in frames if f["flagged"]]
    assert s["nearest"]["max"] == pytest.approx(max(f["nearest"] for f in frames))
    assert s["pos_cm"] == pytest.approx(np.mean([f["pos_cm"] for f in frames]))
    assert -1 <= s["correlation_nearest_pos"]["pearson"] <= 1
    assert doc["map"]["explained"][0] > doc["map"]["explained"][1] > 0
    assert "flagged" in capsys.readouterr().out


def test_a_method_without_a_latent_is_refused(tmp_path, capsys):
    out = tmp_path / "r.png"
    assert main(["latent", "assets/clips/example.bvh", "--method", "ik", "--out", str(out)]) == 2
    assert "ik has no latent space" in capsys.readouterr().err
    assert not out.exists()


@pytest.mark.parametrize(
    ("flags", "message"), [(["--out", "r.jpg"], "PNG"), (["--out", "r.png", "--vae", "x.pt"], "latent map belongs")]
)
def test_bad_options_are_user_errors(tmp_path, capsys, flags, message, monkeypatch):
    monkeypatch.chdir(tmp_path)
    from pathlib import Path

    clip = Path(__file__).resolve().parents[3] / "assets" / "clips" / "example.bvh"
    assert main(["latent", str(clip), *flags]) == 2
    assert message in capsys.readouterr().err
