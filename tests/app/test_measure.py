"""``dragposer-studio gui FILE --measure SECONDS --json OUT``: the smoothness figures, for real."""

from __future__ import annotations

import json
import os
import subprocess
import sys

import pytest

from tests.conftest import REPO

pytestmark = pytest.mark.gui


def test_measure_plays_the_clip_and_writes_plausible_figures(tmp_path):
    out = tmp_path / "measure.json"
    env = {**os.environ, "XDG_CONFIG_HOME": str(tmp_path / "config"), "OMP_NUM_THREADS": "1"}
    env.pop("QT_QPA_PLATFORM", None)  # the real window on the test's X display
    cmd = [
        sys.executable,
        "-m",
        "engine.cli.main",
        "gui",
        str(REPO / "assets" / "clips" / "example.bvh"),
        "--method",
        "ik",
        "--sensors",
        "6",
        "--measure",
        "3",
        "--json",
        str(out),
    ]
    done = subprocess.run(cmd, cwd=REPO, env=env, capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr[-2000:]
    m = json.loads(out.read_text())
    assert {"draws_per_s", "solved_per_s", "frames_skipped", "event_loop_ms", "panels"} <= set(m)
    assert 2.5 <= m["seconds"] <= 10
    assert 0 < m["draws_per_s"] < 200 and 0 < m["solved_per_s"] < 1000
    assert m["frames_skipped"] == 0 and m["pace"] == "every_frame"  # the default solves every frame
    late = m["event_loop_ms"]
    assert 0 <= late["p50"] <= late["p99"] <= late["max"] < 10_000 and late["samples"] > 0
    assert {"view", "timeline", "plot:iterations", "plot:cost", "plot:history", "latent", "status"} <= set(m["panels"])
    view = m["panels"]["view"]
    assert view["updates"] > 0 and 0 < view["mean_ms"] <= view["max_ms"]
    assert len(m["sensors"]) == 6 and m["window"] == [1600, 1000]


def test_measure_rejects_a_non_positive_duration(tmp_path):
    cmd = [sys.executable, "-m", "engine.cli.main", "gui", "--measure", "0"]
    done = subprocess.run(cmd, cwd=REPO, capture_output=True, text=True, timeout=300)
    assert done.returncode == 2 and "--measure" in done.stderr
