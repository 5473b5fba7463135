"""Where the studio's launch time goes: runs ``gui --screenshot OUT --after-frames 1``
with start-up tracing on (:mod:`engine.startup_trace`) and prints each mark's seconds
since launch (the moment this script starts the command) and the CPU seconds its
process had used by then (on a busy machine the CPU column is the steadier one), then
the command's wall time.

    PYTHONPATH=. python research/startup_breakdown.py [--runs 3] [-- extra gui arguments]

Run it under a display (``xvfb-run -a -s "-screen 0 1600x1000x24" python ...``).
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from engine.startup_trace import ENV


def run_once(extra: list[str]) -> list[tuple[float, str, str]]:
    """One launch: ``(seconds since launch, process, its CPU seconds, label)`` rows, the exit last."""
    with tempfile.TemporaryDirectory() as tmp:
        trace = Path(tmp) / "trace.txt"
        cmd = [
            sys.executable,
            "-m",
            "engine.cli.main",
            "gui",
            "--sensors",
            "6",
            "--screenshot",
            str(Path(tmp) / "shot.png"),
            "--after-frames",
            "1",
            *extra,
        ]
        t0 = time.time()
        subprocess.run(cmd, env={**os.environ, ENV: str(trace)}, check=True)
        end = time.time()
        lines = trace.read_text(encoding="utf-8").splitlines() if trace.is_file() else []
    main_pid = lines[0].split()[1] if lines else ""
    rows = []
    for line in lines:
        stamp, pid, cpu, label = line.split(" ", 3)
        rows.append((float(stamp) - t0, "window" if pid == main_pid else "engine", float(cpu), label))
    rows.append((end - t0, "window", float("nan"), "exited (screenshot saved)"))
    return sorted(rows)


def main() -> None:
    """Print the breakdown of each run."""
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--runs", type=int, default=1)
    ap.add_argument("extra", nargs="*", help="more gui arguments (after --)")
    args = ap.parse_args()
    for r in range(args.runs):
        print(f"run {r + 1}")
        print("  since launch  process  its CPU s  mark")
        for t, who, cpu, label in run_once(args.extra):
            print(f"  {t:10.2f} s  {who:7s}  {cpu:9.2f}  {label}")


if __name__ == "__main__":
    main()
