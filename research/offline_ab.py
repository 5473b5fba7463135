"""Offline mode, old code against new, on the same validation files: speed and accuracy.

    PYTHONPATH=. python research/offline_ab.py [--baseline 8610963] [--prepared DIR] [--files N]
        [--max-frames 300] [--sensors 6] [--mode offline] [--method dragposer] [--repeats 1] [FILE.bvh ...]

Both versions of ``engine`` (the baseline revision via ``git archive``, and the working
tree) are loaded in one process (:mod:`ab_versions`), each with its own shipped models,
and run DragPoser (or ``--method``) through their own ``evaluate`` per-clip function on each file in turn,
alternating which goes first, with one torch and one BLAS thread. Per file it prints
each version's thread CPU time and wall time per frame and its metrics, then the
speed-up (old / new, total CPU and wall time) and the metric differences. Files
default to ``dragposer-studio data list --split val --data DIR`` (the first ``--files``).
"""

from __future__ import annotations

import argparse
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
import torch
from threadpoolctl import threadpool_limits

from ab_versions import ROOT, EngineVersion, checkout

METRICS = ("pos_cm", "rot_deg", "vel_cms", "ee_cm", "jitter", "iterations_mean")


def val_files(prepared: Path) -> list[str]:
    cmd = [sys.executable, "-m", "engine.cli.main", "data", "list", "--split", "val", "--data", str(prepared)]
    out = subprocess.run(cmd, cwd=ROOT, capture_output=True, text=True, check=True).stdout
    return [line.strip() for line in out.splitlines() if line.strip()]


def run_one(v: EngineVersion, path: str, a: argparse.Namespace) -> tuple[float, float, dict]:
    """(cpu s, wall s, metrics) of one version on one file."""
    with v:
        from engine.cli.evaluate import evaluate_clip
        from engine.methods import get_method
        from engine.motion.retarget import load_motion

        motion = load_motion(path)
        if a.max_frames:
            motion = motion.slice(0, a.max_frames)
        method = get_method(a.method, mode=a.mode)
        c0, t0 = time.thread_time(), time.perf_counter()
        m = evaluate_clip(motion, method, a.sensors, progress=False)
        return time.thread_time() - c0, time.perf_counter() - t0, {**m, "frames": len(motion)}


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("files", nargs="*", help="BVH files (default: the validation split)")
    ap.add_argument("--baseline", default="8610963", help="old git revision (default: 8610963)")
    ap.add_argument("--files", dest="n_files", type=int, default=9, help="first N validation files (default: 9)")
    ap.add_argument(
        "--prepared",
        type=Path,
        default=ROOT / "prepared",
        help="prepared data folder whose validation split is used (default: ./prepared)",
    )
    ap.add_argument("--max-frames", type=int, default=300)
    ap.add_argument("--sensors", default="6")
    ap.add_argument("--method", default="dragposer", help="method to run in both versions (default: dragposer)")
    ap.add_argument("--mode", default="offline", choices=("offline", "realtime"))
    ap.add_argument("--repeats", type=int, default=1, help="passes over the files (default: 1)")
    a = ap.parse_args()
    torch.set_num_threads(1)
    files = a.files or val_files(a.prepared)[: a.n_files]
    with tempfile.TemporaryDirectory() as tmp, threadpool_limits(limits=1):
        old = EngineVersion(checkout(a.baseline, Path(tmp)), f"old {a.baseline}")
        new = EngineVersion(ROOT, "new (working tree)")
        for v in (old, new):  # warm-up: lazy imports, first-call allocations
            run_one(v, files[0], argparse.Namespace(**{**vars(a), "max_frames": 8}))
        total = {v.label: np.zeros(2) for v in (old, new)}
        metrics: dict[str, list[dict]] = {v.label: [] for v in (old, new)}
        k = 0
        for _ in range(a.repeats):
            for path in files:
                res = {}
                for v in (old, new) if k % 2 == 0 else (new, old):
                    res[v.label] = run_one(v, path, a)
                k += 1
                for v in (old, new):
                    cpu, wall, m = res[v.label]
                    total[v.label] += (cpu, wall)
                    metrics[v.label].append(m)
                    print(
                        f"{Path(path).name:<14} {v.label:<20} cpu {1000 * cpu / m['frames']:8.1f} ms/frame  "
                        f"wall {1000 * wall / m['frames']:8.1f}  "
                        + "  ".join(f"{key} {m[key]:.3f}" for key in METRICS),
                        flush=True,
                    )
        (oc, ow), (nc, nw) = total[old.label], total[new.label]
        print(
            f"\nspeed-up old/new: cpu {oc / nc:.2f}x  wall {ow / nw:.2f}x  "
            f"(cpu {oc:.1f} s vs {nc:.1f} s; {len(files)} files x {a.repeats}, mode {a.mode}, "
            f"max {a.max_frames} frames, sensors {a.sensors}, {a.method})"
        )
        for key in METRICS:
            o = np.array([m[key] for m in metrics[old.label]])
            n = np.array([m[key] for m in metrics[new.label]])
            print(
                f"{key:<16} old {o.mean():8.3f}  new {n.mean():8.3f}  largest |diff| per file {np.abs(o - n).max():.4f}"
            )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
