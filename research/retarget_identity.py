"""Is retargeting's output unchanged? Snapshots of real files, compared bit for bit.

The shipped models and every prepared data set depend on the current retargeting strategy
giving the very same clips; a refactor of ``engine/motion/retarget*.py`` must leave them
bit-identical. ``save`` retargets one file of each rig family of the shared data (BVH and
ASF/AMC, first ``--max-frames`` canonical frames) with each strategy of
:data:`research.retarget_versions.VERSIONS` and with the default (the model card's), and
writes local rotations, root positions, offsets, the per-joint alignments and the report's
figures; ``compare`` says which arrays differ at all::

    PYTHONPATH=. python research/retarget_identity.py save /tmp/before.npz   # on the old tree
    PYTHONPATH=. python research/retarget_identity.py save /tmp/after.npz    # on the new tree
    python research/retarget_identity.py compare /tmp/before.npz /tmp/after.npz
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
MOCAP = ROOT.parent / "shared" / "data" / "mocap"
#: One file per rig family of the shared data.
FILES = (
    "cmu_iclone/005_04.bvh",
    "cmu_mb/07_03.bvh",
    "cmu_daz_cgspeed/07_03.bvh",
    "cmu_daz/indian/04.bvh",
    "dragposer/example.bvh",
    "hdm05/HDM_bd_depositFloorR_001_120.amc",
    "cmu_asf/02/02_01.amc",
)


def snapshot(mocap: Path, max_frames: int) -> dict[str, np.ndarray]:
    """Arrays keyed ``file|strategy|field`` (strategy: a version number or ``default``)."""
    sys.path.insert(0, str(ROOT))
    from engine.motion.retarget import load_with_report
    from research.retarget_versions import VERSIONS

    out: dict[str, np.ndarray] = {}
    for rel in FILES:
        for name, strategy in [("default", None), *((str(v), s) for v, s in VERSIONS.items())]:
            motion, rep = load_with_report(mocap / rel, max_frames=max_frames, strategy=strategy)
            key = f"{rel}|{name}|"
            out[key + "local_rot"] = motion.local_rot
            out[key + "root_pos"] = motion.root_pos
            out[key + "offsets"] = motion.skeleton.offsets
            out[key + "align"] = np.array([np.full(4, np.nan) if a is None else a for a in rep.align or []])
            out[key + "figures"] = np.array(
                [rep.floor_shift, rep.height_m, rep.source_height_m, rep.version, rep.frames]
            )
            out[key + "toe_tips"] = np.array([rep.toe_tips[t] for t in sorted(rep.toe_tips or {})])
            out[key + "joints"] = np.array(
                [*sorted(rep.body_joints or []), "|", *sorted(f"{j}={r}" for j, r in (rep.twist_rules or {}).items())]
            )
    return out


def differing(a: dict[str, np.ndarray], b: dict[str, np.ndarray]) -> list[str]:
    """Keys present in only one snapshot, or whose arrays differ in shape or in any bit
    (NaN equal to NaN)."""
    keys = sorted(set(a) | set(b))
    bad = []
    for k in keys:
        if k not in a or k not in b or a[k].shape != b[k].shape:
            bad.append(k)
        elif a[k].dtype.kind in "USO":
            bad += [k] if not (a[k] == b[k]).all() else []
        elif not np.array_equal(a[k], b[k], equal_nan=True):
            bad.append(k)
    return bad


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    sub = ap.add_subparsers(dest="command", required=True)
    save = sub.add_parser("save", help="retarget the files and write the arrays")
    save.add_argument("out", type=Path)
    save.add_argument("--mocap", type=Path, default=MOCAP)
    save.add_argument("--max-frames", type=int, default=240)
    cmp = sub.add_parser("compare", help="list the arrays that differ between two snapshots")
    cmp.add_argument("a", type=Path)
    cmp.add_argument("b", type=Path)
    args = ap.parse_args(argv)
    if args.command == "save":
        np.savez(args.out, **snapshot(args.mocap, args.max_frames))
        return 0
    a, b = dict(np.load(args.a)), dict(np.load(args.b))
    bad = differing(a, b)
    print(f"{len(set(a) | set(b))} arrays, {len(bad)} differ" + "".join(f"\n  {k}" for k in bad))
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
