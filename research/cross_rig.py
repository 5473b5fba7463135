"""Print how the canonical motion of each CMU take differs between its copies on other rigs.

Every take the shared manifest lists on two or three rigs (``cmu_trial``) is converted from
each rig, and every pair of copies is aligned in time and heading and compared
(:func:`research.retarget_compare.compare_clips`): mean local-rotation difference, the worst
joint, and root-relative positions at one height. The table goes into ``docs/skeleton.md``.
With ``--ablate`` each pair's difference is also split into a constant offset per joint
and what varies over the clip (:func:`research.retarget_ablation.offset_ablation`).

    PYTHONPATH=. python research/cross_rig.py ../shared/data/mocap [--max-frames 1200] [--ablate] [--json OUT.json]
"""

from __future__ import annotations

import argparse
import itertools
import json
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from engine import skeleton as sk  # noqa: E402
from engine.motion.retarget import RETARGET_VERSION, load_motion  # noqa: E402
from research.retarget_ablation import offset_ablation  # noqa: E402
from research.retarget_compare import align_clips, difference, multi_rig_takes  # noqa: E402
from research.retarget_versions import VERSIONS  # noqa: E402

#: Joints of the per-joint ablation table: the left side (the right is alike) and the spine.
ABLATE_JOINTS = (
    "root",
    "lhip",
    "lknee",
    "lankle",
    "ltoe",
    "lowerback",
    "chest",
    "lowerneck",
    "upperneck",
    "lclavicle",
    "lshoulder",
    "lelbow",
    "lwrist",
    "rwrist",
)


def _rounded(v: np.ndarray) -> dict:
    return dict(zip(sk.JOINT_NAMES, np.round(v, 2).tolist()))


def cross_rig_rows(
    mocap: Path, max_frames: int | None = None, version: int = RETARGET_VERSION, ablate: bool = False
) -> list[dict]:
    """One row per pair of copies of a take (see module docs)."""
    rows = []
    for take, paths in multi_rig_takes(mocap).items():
        clips = {p: load_motion(mocap / p, max_frames=max_frames, strategy=VERSIONS[version]) for p in paths}
        for pa, pb in itertools.combinations(paths, 2):
            aligned = align_clips(clips[pa], clips[pb])
            d = difference(aligned)
            extra = {}
            if ablate:
                ab = offset_ablation(clips[pa], clips[pb], aligned)
                extra = {
                    "removed_deg": _rounded(ab.removed_deg),
                    "offset_twist_deg": _rounded(ab.offset_twist_deg),
                    "offset_swing_deg": _rounded(ab.offset_swing_deg),
                    "removed_pos_cm": round(float(ab.removed_pos_cm.mean()), 2),
                }
            worst, worst_deg = d.rot_worst
            rows.append(
                {
                    "take": take,
                    "a": pa.split("/")[0],
                    "b": pb.split("/")[0],
                    "frames": d.frames,
                    "shift": d.shift,
                    "rot_mean_deg": round(d.rot_mean, 2),
                    "worst_joint": worst,
                    "worst_deg": round(worst_deg, 2),
                    "pos_mean_cm": round(d.pos_mean, 2),
                    "pos_worst_cm": round(float(d.pos_cm.max()), 2),
                    "pos_own_cm": round(float(d.pos_own_cm.mean()), 2),
                    "rot_deg": _rounded(d.rot_deg),
                    **extra,
                }
            )
    return rows


def _median(sel: list[dict], key: str, joint: str) -> float:
    return float(np.median([r[key][joint] for r in sel]))


def print_ablation(rows: list[dict]) -> None:
    """Per pair of rigs: the mean and the worst joint (median over the takes) before and
    after removing each joint's constant offset; per joint: the medians of the raw
    difference, of what is left, and of the offset's twist (signed) and swing."""
    pairs = sorted({(r["a"], r["b"]) for r in rows})
    print(
        "\n| rigs | pairs | raw mean (deg) | offset removed | worst joint raw (median) | worst joint removed "
        "| pos raw (cm) | pos removed (cm) |"
    )
    print("|---|---:|---:|---:|---|---|---:|---:|")
    for pair in pairs:
        sel = [r for r in rows if (r["a"], r["b"]) == pair]
        raw = {j: _median(sel, "rot_deg", j) for j in sk.JOINT_NAMES}
        rem = {j: _median(sel, "removed_deg", j) for j in sk.JOINT_NAMES}
        wr, wm = max(raw, key=raw.get), max(rem, key=rem.get)
        print(
            f"| {pair[0]} / {pair[1]} | {len(sel)} | {np.mean([np.mean(list(r['rot_deg'].values())) for r in sel]):.2f} | "
            f"{np.mean([np.mean(list(r['removed_deg'].values())) for r in sel]):.2f} | {wr} {raw[wr]:.1f} | "
            f"{wm} {rem[wm]:.1f} | {np.mean([r['pos_mean_cm'] for r in sel]):.2f} | "
            f"{np.mean([r['removed_pos_cm'] for r in sel]):.2f} |"
        )
    print("\nper joint, median over the takes: raw / offset removed / offset twist (signed) / offset swing (deg)")
    print("| rigs | " + " | ".join(ABLATE_JOINTS) + " |")
    print("|---|" + "---|" * len(ABLATE_JOINTS))
    for pair in pairs:
        sel = [r for r in rows if (r["a"], r["b"]) == pair]
        cells = [
            f"{_median(sel, 'rot_deg', j):.1f} / {_median(sel, 'removed_deg', j):.1f} / "
            f"{_median(sel, 'offset_twist_deg', j):+.0f} / {_median(sel, 'offset_swing_deg', j):.0f}"
            for j in ABLATE_JOINTS
        ]
        print(f"| {pair[0]} / {pair[1]} | " + " | ".join(cells) + " |")


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("mocap", type=Path)
    ap.add_argument("--max-frames", type=int, default=None, help="canonical frames read per clip")
    ap.add_argument("--json", type=Path, default=None)
    ap.add_argument(
        "--version",
        type=int,
        choices=sorted(VERSIONS),
        default=RETARGET_VERSION,
        help="retargeting definition (default: the current one)",
    )
    ap.add_argument(
        "--ablate", action="store_true", help="also split each difference into a constant offset per joint and the rest"
    )
    args = ap.parse_args(argv)
    rows = cross_rig_rows(args.mocap, args.max_frames, args.version, args.ablate)
    print(
        "| rigs | pairs | rot mean (deg) | worst pair mean | worst joint mean (joint, take) | pos mean (cm) | worst pos (cm) |"
    )
    print("|---|---:|---:|---:|---|---:|---:|")
    for pair in sorted({(r["a"], r["b"]) for r in rows}):
        sel = [r for r in rows if (r["a"], r["b"]) == pair]
        w = max(sel, key=lambda r: r["worst_deg"])
        print(
            f"| {pair[0]} / {pair[1]} | {len(sel)} | {np.mean([r['rot_mean_deg'] for r in sel]):.2f} | "
            f"{max(r['rot_mean_deg'] for r in sel):.2f} | {w['worst_deg']:.1f} ({w['worst_joint']}, {w['take']}) | "
            f"{np.mean([r['pos_mean_cm'] for r in sel]):.2f} | {max(r['pos_mean_cm'] for r in sel):.2f} |"
        )
    joints = {j: max(r["rot_deg"][j] for r in rows) for j in sk.JOINT_NAMES}
    print("\nworst take per joint (deg):", ", ".join(f"{j} {v:.1f}" for j, v in joints.items()))
    if args.ablate:
        print_ablation(rows)
    if args.json:
        args.json.write_text(json.dumps(rows, indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main())
