"""Print how the canonical motion of each CMU take differs between its copies on other rigs.

Every take the shared manifest lists on two or three rigs (``cmu_trial``) is converted from
each rig, and every pair of copies is aligned in time and heading and compared
(:func:`engine.motion.retarget_compare.compare_clips`): mean local-rotation difference, the worst
joint, and root-relative positions at one height. The table goes into ``docs/skeleton.md``.

    PYTHONPATH=. python scripts/cross_rig.py ../shared/data/mocap [--max-frames 1200] [--json OUT.json]
"""

from __future__ import annotations

import argparse
import itertools
import json
import sys
from pathlib import Path

import numpy as np

from engine import skeleton as sk
from engine.motion.retarget import RETARGET_VERSION, RETARGET_VERSIONS, load_motion
from engine.motion.retarget_compare import compare_clips, multi_rig_takes


def cross_rig_rows(mocap: Path, max_frames: int | None = None, version: int = RETARGET_VERSION) -> list[dict]:
    """One row per pair of copies of a take (see module docs)."""
    rows = []
    for take, paths in multi_rig_takes(mocap).items():
        clips = {p: load_motion(mocap / p, max_frames=max_frames, version=version) for p in paths}
        for pa, pb in itertools.combinations(paths, 2):
            d = compare_clips(clips[pa], clips[pb])
            worst, worst_deg = d.rot_worst
            rows.append({"take": take, "a": pa.split("/")[0], "b": pb.split("/")[0], "frames": d.frames,
                         "shift": d.shift, "rot_mean_deg": round(d.rot_mean, 2), "worst_joint": worst,
                         "worst_deg": round(worst_deg, 2), "pos_mean_cm": round(d.pos_mean, 2),
                         "pos_worst_cm": round(float(d.pos_cm.max()), 2), "pos_own_cm": round(float(d.pos_own_cm.mean()), 2),
                         "rot_deg": dict(zip(sk.JOINT_NAMES, np.round(d.rot_deg, 2).tolist()))})  # fmt: skip
    return rows


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("mocap", type=Path)
    ap.add_argument("--max-frames", type=int, default=None, help="canonical frames read per clip")
    ap.add_argument("--json", type=Path, default=None)
    ap.add_argument("--version", type=int, choices=RETARGET_VERSIONS, default=RETARGET_VERSION,
                    help="retargeting definition (default: the current one)")
    args = ap.parse_args(argv)
    rows = cross_rig_rows(args.mocap, args.max_frames, args.version)
    print("| rigs | pairs | rot mean (deg) | worst pair mean | worst joint mean (joint, take) | pos mean (cm) | worst pos (cm) |")
    print("|---|---:|---:|---:|---|---:|---:|")
    for pair in sorted({(r["a"], r["b"]) for r in rows}):
        sel = [r for r in rows if (r["a"], r["b"]) == pair]
        w = max(sel, key=lambda r: r["worst_deg"])
        print(f"| {pair[0]} / {pair[1]} | {len(sel)} | {np.mean([r['rot_mean_deg'] for r in sel]):.2f} | "
              f"{max(r['rot_mean_deg'] for r in sel):.2f} | {w['worst_deg']:.1f} ({w['worst_joint']}, {w['take']}) | "
              f"{np.mean([r['pos_mean_cm'] for r in sel]):.2f} | {max(r['pos_mean_cm'] for r in sel):.2f} |")  # fmt: skip
    joints = {j: max(r["rot_deg"][j] for r in rows) for j in sk.JOINT_NAMES}
    print("\nworst take per joint (deg):", ", ".join(f"{j} {v:.1f}" for j, v in joints.items()))
    if args.json:
        args.json.write_text(json.dumps(rows, indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main())
