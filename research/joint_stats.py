"""Hinge-axis alignment and twist statistics per joint, on every clip of a data folder.

Each clip is retargeted to the canonical rig (``engine.motion.retarget``) and measured with
:func:`engine.motion.joint_stats.joint_report`. Clips are grouped by their top folder
(``cmu_daz``, ``cmu_iclone``, ``dragposer``); the canonical rig's own clips
(``--canonical``, default ``dragposer``) give the reference hinge axis of each joint.

Per joint and group it prints the range of the clips' median twist (degrees), the
largest 90th-percentile |twist| (in the JSON), and the hinge alignment: the smallest and
the median |cos| between a clip's hinge axis and the canonical clips' mean axis (1 = the
same axis; meaningful for the hinge joints, knees and elbows)::

    PYTHONPATH=. python research/joint_stats.py ../shared/data/mocap --json runs/joint_stats.json
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

from engine.motion.joint_stats import joint_report, summarize
from engine.motion.retarget import load_with_report


def collect(root: Path, progress: bool = True) -> dict[str, dict[str, dict]]:
    """``{group: {clip: joint_report}}`` for every ``*.bvh`` under ``root``."""
    out: dict[str, dict[str, dict]] = {}
    files = sorted(root.rglob("*.bvh"))
    for i, path in enumerate(files, 1):
        motion, _ = load_with_report(path)
        rel = path.relative_to(root)
        out.setdefault(rel.parts[0], {})[str(rel)] = joint_report(motion.local_rot, motion.skeleton.offsets)
        if progress:
            print(f"\r{i}/{len(files)} {rel}", end="", file=sys.stderr, flush=True)
    if progress:
        print(file=sys.stderr)
    return out


def markdown(table: dict[str, dict[str, dict]], canonical: str) -> str:
    groups = [canonical] + sorted(g for g in next(iter(table.values())) if g != canonical)
    head = "| joint | " + " | ".join(f"{g} twist median (deg) | {g} hinge cos min / median" for g in groups) + " |"
    lines = [head, "|---" * (1 + 2 * len(groups)) + "|"]
    for joint, row in table.items():
        cells = []
        for g in groups:
            lo, hi = row[g]["twist_median"]
            cells += [
                f"{lo:+.0f}..{hi:+.0f}",
                f"{row[g]['hinge_alignment_min']:.2f} / {row[g]['hinge_alignment_median']:.2f}",
            ]
        lines.append(f"| {joint} | " + " | ".join(cells) + " |")
    counts = ", ".join(f"{g}: {table['lknee'][g]['clips']} clips" for g in groups)
    return "\n".join(lines) + f"\n\n({counts})\n"


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("root", type=Path, help="data folder (e.g. ../shared/data/mocap)")
    p.add_argument("--canonical", default="dragposer", help="group of the canonical rig's own clips")
    p.add_argument("--json", type=Path, help="also write the per-clip reports and the summary here")
    args = p.parse_args(argv)
    groups = collect(args.root)
    if args.canonical not in groups:
        p.error(f"no {args.canonical}/ folder under {args.root}")
    table = summarize(groups, args.canonical)
    print(markdown(table, args.canonical))
    if args.json:
        from engine.atomic import write_text

        args.json.parent.mkdir(parents=True, exist_ok=True)
        write_text(args.json, json.dumps({"summary": table, "clips": groups}, indent=1))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
