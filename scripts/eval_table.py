"""The optimizer issue's evaluation: dragposer against the IK baseline on the validation
files, sensor presets 6, 4, 3-hip-hands and 3-head-hands, realtime and offline.

    .venv/bin/python scripts/eval_table.py OUT_DIR [--jobs 2] [--realtime-frames 300]
                                                   [--offline-frames 120] [--table-only]
                                                   [--methods dragposer ik]

Each run is one ``dragposer-studio evaluate`` call (its JSON lands in OUT_DIR, runs that
already have a JSON are skipped); the markdown table of the totals is printed at the end.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
CLI = str(ROOT / ".venv" / "bin" / "dragposer-studio")
PRESETS = ("6", "4", "3-hip-hands", "3-head-hands")
MODES = ("realtime", "offline")
METHODS = ("dragposer", "ik")


def run(out: Path, files: list[str], method: str, preset: str, mode: str, frames: int) -> str:
    target = out / f"{method}-{preset}-{mode}.json"
    if target.is_file():
        return f"kept {target.name}"
    cmd = [CLI, "evaluate", *files, "--method", method, "--sensors", preset, "--mode", mode,
           "--max-frames", str(frames), "--no-progress", "--json", str(target),
           "--jobs", "1"]  # this script runs the evaluations side by side itself  # fmt: skip
    env = {**os.environ, "OMP_NUM_THREADS": "1"}
    res = subprocess.run(cmd, capture_output=True, text=True, env=env)
    (out / f"{method}-{preset}-{mode}.txt").write_text(" ".join(cmd) + "\n\n" + res.stdout + res.stderr)
    return f"{'done' if res.returncode == 0 else 'FAILED'} {target.name}"


def table(out: Path) -> str:
    rows = ["| preset | mode | method | Pos cm | Rot deg | Vel cm/s | EE cm | Jitter | ms/frame |",
            "|---|---|---|---:|---:|---:|---:|---:|---:|"]  # fmt: skip
    for preset in PRESETS:
        for mode in MODES:
            for method in METHODS:
                f = out / f"{method}-{preset}-{mode}.json"
                if not f.is_file():
                    continue
                t = json.loads(f.read_text())["total"]
                rows.append(f"| {preset} | {mode} | {method} | {t['pos_cm']:.2f} | {t['rot_deg']:.1f} | "
                            f"{t['vel_cms']:.1f} | {t['ee_cm']:.2f} | {t['jitter']:.1f} | {t['ms_per_frame']:.0f} |")
    return "\n".join(rows)


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("out", type=Path)
    ap.add_argument("--jobs", type=int, default=2)
    ap.add_argument("--realtime-frames", type=int, default=300)
    ap.add_argument("--offline-frames", type=int, default=120)
    ap.add_argument("--table-only", action="store_true")
    ap.add_argument("--methods", nargs="+", default=list(METHODS), choices=METHODS,
                    help="run only these methods (e.g. ik while the models are still training)")
    args = ap.parse_args()
    args.out.mkdir(parents=True, exist_ok=True)
    if not args.table_only:
        files = subprocess.run([CLI, "data", "list", "--split", "val"], capture_output=True, text=True,
                               check=True).stdout.split()  # fmt: skip
        jobs = [(m, p, mode, args.realtime_frames if mode == "realtime" else args.offline_frames)
                for p in PRESETS for mode in MODES for m in args.methods]  # fmt: skip
        jobs.sort(key=lambda j: (j[0] == "ik", j[2] == "realtime"))  # slowest first
        with ThreadPoolExecutor(args.jobs) as pool:
            for msg in pool.map(lambda j: run(args.out, files, *j), jobs):
                print(msg, flush=True)
    print(table(args.out))
    return 0


if __name__ == "__main__":
    sys.exit(main())
