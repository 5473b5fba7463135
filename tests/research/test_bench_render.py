"""research/bench_render.py runs render and reports its time against the clip (no timing asserted)."""

from __future__ import annotations

import re

import pytest

from engine.motion.bvh import save_motion_bvh
from engine.studio.clips import load_clip

from .script_loader import ROOT, load_script


@pytest.mark.slow  # a render subprocess: 5 s idle, 18 s on the loaded machine
def test_a_run_and_a_profile_report_against_the_clip(tmp_path, capsys):
    clip = tmp_path / "short.bvh"
    save_motion_bvh(clip, load_clip(ROOT / "assets" / "clips" / "example.bvh").slice(0, 12))
    bench = load_script("bench_render")
    assert bench.main([str(clip), "--size", "64x48", "--args", "--view sticks"]) == 0
    out = capsys.readouterr().out
    assert "12 frames at 60 fps = 0.20 s" in out
    assert re.search(r"run 1 +64x48 .*: +[\d.]+ s = [\d.]+ x the clip, CPU +[\d.]+ s .* ok", out)
    assert bench.main([str(clip), "--size", "64x48", "--args", "--view sticks", "--profile"]) == 0
    out = capsys.readouterr().out
    assert re.search(r"64x48 .* frames [\d.]+ ms each", out) and re.search(r"render: +[\d.]+ ms per frame", out)
