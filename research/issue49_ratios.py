"""Same-minutes ratios of ``dragposer-studio bench`` between two source trees (issue 49).

    python research/issue49_ratios.py BASE_TREE [CANDIDATE_TREE] [--repeats 3] [--frames 600]
                                      [--clip FILE.bvh] [-- EXTRA BENCH ARGS ...]

Runs ``bench --method dragposer --sensors 6 <clip> --frames N`` (plus the extra
arguments, e.g. ``--mode offline`` or ``--scene ...``) in a fresh process per run, each
tree on its own ``PYTHONPATH`` with one BLAS / OpenMP thread, alternating the trees
(and which goes first in each round), and prints every run's figures, each tree's
medians and the candidate / base ratio of each median. On a loaded machine only the
ratios mean anything; separate processes see the same load only when they alternate
quickly, so use at least three repeats. ``CANDIDATE_TREE`` defaults to this tree.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
#: The issue's clip (``../shared`` beside the checkout); the bundled one when it is absent.
CLIP = ROOT.parent / "shared" / "data" / "mocap" / "dragposer" / "example.bvh"
FIELDS = ("ms_per_iteration_median", "ms_per_frame_median", "frames_per_s")
PARTS = ("decoder", "fk_losses", "backward", "step")


def run(tree: Path, frames: int, extra: list[str], clip: Path) -> dict[str, float]:
    """One bench of ``tree``: its DragPoser figures and per-iteration breakdown."""
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / "bench.json"
        cmd = [sys.executable, "-m", "engine.cli.main", "bench", "--method", "dragposer", "--sensors", "6"]
        cmd += [str(clip), "--frames", str(frames), "--json", str(out), *extra]
        env = dict(os.environ, PYTHONPATH=str(tree), OMP_NUM_THREADS="1", OPENBLAS_NUM_THREADS="1")
        subprocess.run(cmd, cwd=tree, env=env, check=True, capture_output=True)
        m = json.loads(out.read_text())["methods"][0]
    row = {f: float(m[f]) if m[f] is not None else float("nan") for f in FIELDS}
    parts = m["breakdown_ms"] or {}  # none for the batched offline solve
    row.update({p: float(parts.get(p, float("nan"))) for p in PARTS})
    return row


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("base", type=Path)
    ap.add_argument("candidate", type=Path, nargs="?", default=ROOT)
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--frames", type=int, default=600)
    ap.add_argument("--clip", type=Path, default=CLIP if CLIP.exists() else ROOT / "assets" / "clips" / "example.bvh")
    argv = sys.argv[1:]
    cut = argv.index("--") if "--" in argv else len(argv)
    a, extra = ap.parse_args(argv[:cut]), argv[cut + 1 :]  # after --: more bench arguments
    trees = {"base": a.base.resolve(), "candidate": a.candidate.resolve()}
    rows: dict[str, list[dict[str, float]]] = {k: [] for k in trees}
    keys = FIELDS + PARTS
    print("run        " + " ".join(f"{k[:12]:>12}" for k in keys))
    for i in range(a.repeats):
        for name in list(trees)[:: 1 if i % 2 == 0 else -1]:
            row = run(trees[name], a.frames, extra, a.clip.resolve())
            rows[name].append(row)
            print(f"{name:10} " + " ".join(f"{row[k]:12.3f}" for k in keys), flush=True)
    med = {n: {k: statistics.median(r[k] for r in rows[n]) for k in keys} for n in trees}
    for n in trees:
        print(f"median {n:10} " + " ".join(f"{med[n][k]:12.3f}" for k in keys))
    print("candidate / base  " + " ".join(f"{med['candidate'][k] / med['base'][k]:12.3f}" for k in keys))


if __name__ == "__main__":
    main()
