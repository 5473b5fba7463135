"""Per-iteration cost of user constraints: six trackers alone against the trackers plus a
scene's constraints, on the solver's fast and reference paths, interleaved in one process.

Each configuration runs ``REPEATS`` times in turn (sensors fast, scene fast, scene
reference, sensors reference) through ``bench``'s own timing
(:func:`engine.cli.bench.bench_method`); the lowest median of each is reported, and
its ratio to the sensors-only fast path. On a shared machine only the ratios mean
something; absolute figures are taken on an idle one.

    PYTHONPATH=. OMP_NUM_THREADS=1 python research/bench_constraints.py \\
        [--scene assets/scenes/look_floor_pin_distance.json] [--frames 300] [--iterations 10] [--repeats 3] [--json OUT]
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

from engine.atomic import write_text
from engine.cli.bench import DEFAULT_CLIP, bench_method
from engine.motion.retarget import load_motion
from engine.scene import load_scene
from engine.tracking import simulate

REPO = Path(__file__).resolve().parents[1]


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--scene", type=Path, default=REPO / "assets" / "scenes" / "look_floor_pin_distance.json")
    p.add_argument("--frames", type=int, default=300)
    p.add_argument("--warmup", type=int, default=10)
    p.add_argument("--iterations", type=int, default=10)
    p.add_argument("--repeats", type=int, default=3)
    p.add_argument("--reference-frames", type=int, default=60, help="frames timed on the reference path (slow)")
    p.add_argument("--json", type=Path)
    args = p.parse_args()
    motion = load_motion(DEFAULT_CLIP)
    tracking = simulate(motion, "6")
    scene = load_scene(args.scene)[0]
    configs = [
        ("sensors fast", [], True, args.frames),
        ("scene fast", scene, True, args.frames),
        ("scene reference", scene, False, args.reference_frames),
        ("sensors reference", [], False, args.reference_frames),
    ]
    rows: dict[str, list[dict]] = {}
    for _ in range(args.repeats):
        for label, cons, fast, frames in configs:
            r = bench_method(
                "dragposer",
                motion,
                tracking,
                frames,
                args.warmup,
                cons,
                mode="realtime",
                iterations=args.iterations,
                fast=fast,
            )
            rows.setdefault(label, []).append(r)
    base = min(r["ms_per_iteration_median"] for r in rows["sensors fast"])
    out = {}
    print(f"{DEFAULT_CLIP.name}, sensors 6, {args.iterations} iterations, scene {args.scene.name}")
    for label, runs in rows.items():
        best = min(runs, key=lambda r: r["ms_per_iteration_median"])
        it = best["ms_per_iteration_median"]
        out[label] = {
            "ms_per_iteration_median": it,
            "ratio_to_sensors_fast": it / base,
            "ms_per_frame_median": min(r["ms_median"] for r in runs),
            "breakdown_ms": best["breakdown_ms"],
        }
        parts = " ".join(f"{k} {v:.3f}" for k, v in best["breakdown_ms"].items())
        print(
            f"{label:<18} {it:7.3f} ms/it  {it / base:5.2f}x  {out[label]['ms_per_frame_median']:8.2f} ms/frame  ({parts})"
        )
    if args.json:
        write_text(args.json, json.dumps(out, indent=1))


if __name__ == "__main__":
    main()
