#!/usr/bin/env python3
"""Measure the live-tracker targets of docs/trackers.md: `send` -> `live` on 127.0.0.1.

Runs, one after the other (never two solvers at once):

1. clean: six trackers, 60 fps; frames solved, latency p50/p95, error against the clip,
   and `reconstruct --trackers` on the recording for the offline error;
2. lossy: 5 % of packets dropped and 2 cm position noise; the same figures, and whether
   `live` finished on its own (no crash, no stall);
3. calibration: subjects scaled by 0.9 and 1.1, a 2 s T-pose first, trackers mounted as
   real devices; calibrated height against the true one.

Usage (from the repository root):
    PYTHONPATH=$PWD python research/measure_trackers.py [--clip CLIP.bvh] [--method dragposer]
        [--port 39600] [--out-dir runs/trackers] [--json OUT.json]
Prints a markdown table; every figure also sits in OUT-DIR/*.json.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import time
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
CLI = [sys.executable, "-m", "engine.cli.main"]


def _live_and_send(out: Path, name: str, port: int, live_args: list[str], send_args: list[str], clip: Path) -> dict:
    stats = out / f"{name}.live.json"
    rec = out / f"{name}.rec.jsonl"
    cmd = [
        *CLI,
        "live",
        "--listen",
        f"127.0.0.1:{port}",
        "--record",
        str(rec),
        "--out",
        str(out / f"{name}.live.bvh"),
        "--json",
        str(stats),
        "--idle-stop",
        "3",
        "--duration",
        "600",
        "--no-progress",
        *live_args,
    ]
    env = {**os.environ, "PYTHONPATH": str(REPO)}
    live = subprocess.Popen(cmd, stderr=subprocess.PIPE, stdout=subprocess.PIPE, text=True, env=env)
    line = ""
    while "listening" not in line:
        line = live.stderr.readline()
        if not line and live.poll() is not None:
            raise SystemExit(f"live failed to start: {live.stdout.read()}")
    t0 = time.perf_counter()
    send = subprocess.run(
        [*CLI, "send", str(clip), "--to", f"127.0.0.1:{port}", "--no-progress", *send_args],
        env=env,
        capture_output=True,
        text=True,
    )
    sent = time.perf_counter() - t0
    try:
        live_out, _ = live.communicate(timeout=120)
        stalled = False
    except subprocess.TimeoutExpired:
        live.kill()
        live_out, stalled = "", True
    result = {
        "name": name,
        "live_exit": live.returncode,
        "stalled": stalled,
        "send_s": sent,
        "send": send.stdout.strip() + send.stderr.strip(),
        "live_report": live_out.strip(),
    }
    if stats.is_file():
        result["live"] = json.loads(stats.read_text())
    result["recording"] = str(rec)
    return result


def _offline(out: Path, name: str, rec: str, args: list[str]) -> dict:
    stats = out / f"{name}.offline.json"
    subprocess.run(
        [
            *CLI,
            "reconstruct",
            "--trackers",
            rec,
            "--out",
            str(out / f"{name}.offline.bvh"),
            "--json",
            str(stats),
            "--no-progress",
            *args,
        ],
        check=True,
        env={**os.environ, "PYTHONPATH": str(REPO)},
        capture_output=True,
    )
    return json.loads(stats.read_text())


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--clip", type=Path, default=REPO / "assets" / "clips" / "example.bvh")
    ap.add_argument("--method", default="dragposer")
    ap.add_argument("--port", type=int, default=39600)
    ap.add_argument("--out-dir", type=Path, default=REPO / "runs" / "trackers")
    ap.add_argument("--json", type=Path)
    ap.add_argument("--only", choices=("clean", "lossy", "calibration"), action="append")
    ap.add_argument("--frame-budget", type=float, metavar="MS", help="passed to live (default: live's own)")
    a = ap.parse_args()
    a.out_dir.mkdir(parents=True, exist_ok=True)
    only = set(a.only or ("clean", "lossy", "calibration"))
    ref = ["--reference", str(a.clip), "--method", a.method]
    budget = [] if a.frame_budget is None else ["--frame-budget", str(a.frame_budget)]
    rows, report = [], {}
    for name, send_args in (("clean", []), ("lossy", ["--drop", "0.05", "--noise-pos", "0.02"])):
        if name not in only:
            continue
        r = _live_and_send(a.out_dir, name, a.port, ref + budget, send_args, a.clip)
        r["offline"] = _offline(a.out_dir, name, r["recording"], ref)
        live, off = r.get("live", {}), r["offline"]
        le, oe = live.get("reference", {}).get("pos_cm"), off["reference"]["pos_cm"]
        it = live.get("iterations") or {}
        its = f"{it['mean']:.1f} ({it['min']}, {live.get('frame_budget_ms') or 0:.1f} ms)" if it.get("mean") else "-"
        rows.append(
            f"| {name} | {live.get('frames_received')} | {100 * (live.get('solved_fraction') or 0):.1f} % | "
            f"{live['latency_ms']['p50']:.1f} / {live['latency_ms']['p95']:.1f} ms | {its} | {le:.2f} cm | "
            f"{oe:.2f} cm | {le - oe:+.2f} cm | exit {r['live_exit']}, stalled {r['stalled']} |"
        )
        report[name] = r
    cal_rows = []
    if "calibration" in only:
        for f in (0.9, 1.1):
            name = f"calibration-{f}"
            r = _live_and_send(
                a.out_dir,
                name,
                a.port,
                ["--calibrate", "2", "--method", a.method],
                ["--tpose", "2.2", "--scale", str(f), "--hardware-offsets"],
                a.clip,
            )
            true_h = float(r["send"].split("subject height ")[1].split(" m")[0])
            h = r["live"]["skeleton_height_m"]
            cal_rows.append(
                f"| x{f} | {true_h:.3f} m | {h:.3f} m | {100 * (h / true_h - 1):+.2f} % | "
                f"{r['live']['calibration']['pose']} |"
            )
            report[name] = r
    if rows:
        print(
            "| run | frames | solved | latency p50 / p95 | iterations mean (min, budget) | live error | offline error "
            "| live - offline | end |"
        )
        print("|---|---|---|---|---|---|---|---|---|")
        print("\n".join(rows))
    if cal_rows:
        print("\n| subject | true height | calibrated | error | pose |\n|---|---|---|---|---|")
        print("\n".join(cal_rows))
    if a.json:
        sys.path.insert(0, str(REPO))  # engine importable even without PYTHONPATH
        from engine.atomic import write_text

        a.json.parent.mkdir(parents=True, exist_ok=True)
        write_text(a.json, json.dumps(report, indent=2))
    return 0


if __name__ == "__main__":
    sys.exit(main())
