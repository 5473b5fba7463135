"""``--jobs``: worker processes give the serial run's results, in file order."""

from __future__ import annotations

import json

import pytest

from engine.cli.main import main
from engine.motion.bvh import save_motion_bvh

TIMING = {"ms_per_frame"}


@pytest.fixture
def two_clips(synthetic_motion, tmp_path):
    a, b = tmp_path / "b_first.bvh", tmp_path / "a_second.bvh"  # file order, not name order
    save_motion_bvh(a, synthetic_motion.slice(0, 40))
    save_motion_bvh(b, synthetic_motion.slice(50, 90))
    return [a, b]


def _metrics(path):
    doc = json.loads(path.read_text())
    return {f: {k: v for k, v in m.items() if k not in TIMING} for f, m in doc["files"].items()}, doc


@pytest.mark.slow
def test_evaluate_jobs_matches_serial_run(two_clips, tmp_path):
    out = {}
    for jobs in (1, 2):
        out[jobs] = tmp_path / f"eval{jobs}.json"
        args = [
            "evaluate",
            *map(str, two_clips),
            "--method",
            "dragposer",
            "--max-frames",
            "12",
            "--no-progress",
            "--jobs",
            str(jobs),
            "--json",
            str(out[jobs]),
        ]
        assert main(args) == 0
    serial, doc1 = _metrics(out[1])
    parallel, doc2 = _metrics(out[2])
    assert list(parallel) == [str(p) for p in two_clips]
    assert parallel == serial  # bit-identical metrics
    assert {k: v for k, v in doc1["total"].items() if k not in TIMING} == {
        k: v for k, v in doc2["total"].items() if k not in TIMING
    }


@pytest.mark.slow
def test_reconstruct_several_inputs_in_workers_writes_what_a_serial_run_writes(two_clips, tmp_path, capsys):
    for jobs in (1, 2):
        args = [
            "reconstruct",
            *map(str, two_clips),
            "--out-dir",
            str(tmp_path / f"out{jobs}"),
            "--max-frames",
            "10",
            "--no-progress",
            "--jobs",
            str(jobs),
        ]
        assert main(args) == 0
    text = capsys.readouterr().out
    assert text.index("b_first") < text.index("a_second")  # summaries in file order
    for clip in two_clips:
        one, two = ((tmp_path / f"out{j}" / clip.name).read_bytes() for j in (1, 2))
        assert one == two


def test_reconstruct_needs_out_dir_for_several_inputs(two_clips, capsys):
    assert main(["reconstruct", *map(str, two_clips), "--out", "x.bvh"]) == 2
    assert "--out-dir" in capsys.readouterr().err
