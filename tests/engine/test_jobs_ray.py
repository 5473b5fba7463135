"""``--executor ray``: the per-file jobs on a Ray instance give the ``--jobs`` results, in file order."""

from __future__ import annotations

import json

import pytest

from engine.cli.main import main
from tests.engine.test_jobs import two_clips  # noqa: F401 (the same two files, in file order)

TIMING = {"ms_per_frame"}


@pytest.fixture(scope="module")
def local_ray():
    ray = pytest.importorskip("ray", reason="Ray is not installed (the optional 'cluster' extra)")
    ray.init(num_cpus=2, include_dashboard=False, log_to_driver=False, configure_logging=False)
    yield ray
    ray.shutdown()


def _without_timing(doc: dict) -> dict:
    return {
        "files": {f: {k: v for k, v in m.items() if k not in TIMING} for f, m in doc["files"].items()},
        "total": {k: v for k, v in doc["total"].items() if k not in TIMING},
    }


@pytest.mark.slow
def test_evaluate_and_reconstruct_on_ray_match_the_local_jobs(local_ray, two_clips, tmp_path, capsys):  # noqa: F811
    docs = {}
    for how in (["--jobs", "1"], ["--executor", "ray"]):
        out = tmp_path / f"{how[-1]}.json"
        args = [
            "evaluate",
            *map(str, two_clips),
            "--method",
            "dragposer",
            "--max-frames",
            "8",
            "--no-progress",
            *how,
            "--json",
            str(out),
        ]
        assert main(args) == 0
        docs[how[-1]] = json.loads(out.read_text())
    assert list(docs["ray"]["files"]) == [str(p) for p in two_clips]
    assert _without_timing(docs["ray"]) == _without_timing(docs["1"])
    capsys.readouterr()
    for how in (["--jobs", "1"], ["--executor", "ray"]):
        args = [
            "reconstruct",
            *map(str, two_clips),
            "--out-dir",
            str(tmp_path / how[-1]),
            "--max-frames",
            "6",
            "--no-progress",
            *how,
        ]
        assert main(args) == 0
    text = capsys.readouterr().out
    assert text.rindex("b_first") < text.rindex("a_second")  # summaries in file order
    for clip in two_clips:
        assert (tmp_path / "1" / clip.name).read_bytes() == (tmp_path / "ray" / clip.name).read_bytes()


@pytest.mark.slow
def test_a_worker_error_on_ray_is_the_one_line_user_error(local_ray, tmp_path, capsys):
    bad = tmp_path / "bad.bvh"
    bad.write_text("HIERARCHY\nROOT\n")
    assert main(["evaluate", str(bad), str(bad), "--method", "ik", "--no-progress", "--executor", "ray"]) == 2
    assert "bad.bvh" in capsys.readouterr().err


def test_address_without_ray_executor_is_a_user_error(two_clips, capsys):  # noqa: F811 (the imported fixture)
    assert main(["evaluate", str(two_clips[0]), "--method", "ik", "--address", "ray://x:1"]) == 2
    assert "--address" in capsys.readouterr().err
