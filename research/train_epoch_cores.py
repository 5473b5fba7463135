"""One VAE training epoch of the shipped recipe on the two cores, several ways, two revisions.

Issue 48 asks for an epoch on the 2-core CPU at a third of the time of 1f2a60e's. The
per-step figures of ``research/train_step_ab.py`` are CPU time at one thread; this script
times whole epochs (data loading and validation included) by the wall clock, each way
of using the two cores that a user has:

* ``1x1``: one process, one torch thread (what docs/training.md advises on a busy machine);
* ``1x2``: one process, two torch threads;
* ``2x1``: two processes under ``torch.distributed.run`` (gloo), one thread each, each
  with half the batch (``batch_size`` 128 per process: the same 256 poses a step).

Each run starts from the same seed and trains one epoch (``stop_after=1``, no time budget);
the table gives its wall seconds and the validation error after it (float rounding and,
for ``2x1``, other random draws make trajectories part, so compare those within about
0.1 cm). Run it on an idle machine, nothing else timing::

    PYTHONPATH=. python research/train_epoch_cores.py --baseline /tmp/t_1f2 --data prepared \
        --ways 1x1,1x2,2x1 --baseline-ways 1x1,1x2

``--baseline`` is a plain copy of the older revision (``git archive 1f2a60e | tar -x -C
/tmp/t_1f2``); it runs with this checkout's interpreter and the same prepared data.
"""

from __future__ import annotations

import argparse
import csv
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
RECIPE = ["--set", "bone_scale=0.15", "--set", "stop_after=1", "--set", "minutes=0"]


def run_epoch(tree: Path, way: str, data: Path, out: Path) -> tuple[float, float]:
    """Wall seconds of one epoch in ``tree`` the ``way`` given, and its validation cm."""
    procs, threads = (int(n) for n in way.split("x"))
    env = {**os.environ, "OMP_NUM_THREADS": str(threads), "PYTHONPATH": str(tree)}
    train = ["-m", "engine.cli.main", "train", "vae", "--data", str(data), "--out", str(out)]
    train += ["--config", str(tree / "assets/models/vae.toml"), "--quiet", *RECIPE]
    if procs > 1:
        train += ["--set", f"batch_size={256 // procs}"]
        cmd = [sys.executable, "-m", "torch.distributed.run", "--standalone", f"--nproc_per_node={procs}", *train]
    else:
        cmd = [sys.executable, *train]
    t0 = time.perf_counter()
    subprocess.run(cmd, cwd=tree, env=env, check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    wall = time.perf_counter() - t0
    with open(out / "losses.csv") as f:
        rows = list(csv.DictReader(f))
    return wall, float(rows[-1]["val_pos_cm"])


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--baseline", type=Path, required=True, help="a plain copy of the older revision")
    ap.add_argument("--data", type=Path, default=ROOT / "prepared")
    ap.add_argument("--ways", default="1x1,1x2,2x1", help="this checkout's ways (processes x threads)")
    ap.add_argument("--baseline-ways", default="1x1,1x2", help="the baseline's ways")
    a = ap.parse_args()
    data = a.data.resolve()
    runs = [(a.baseline.resolve(), w) for w in a.baseline_ways.split(",") if w]
    runs += [(ROOT, w) for w in a.ways.split(",") if w]
    print(f"{'tree':<28} {'way':>4} {'epoch s':>8} {'val cm':>7}", flush=True)
    for tree, way in runs:
        with tempfile.TemporaryDirectory() as tmp:
            wall, val = run_epoch(tree, way, data, Path(tmp) / "run")
        print(f"{str(tree):<28} {way:>4} {wall:8.1f} {val:7.3f}", flush=True)


if __name__ == "__main__":
    main()
