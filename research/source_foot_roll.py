"""Is a foot rolled over in the *source* file, before any retargeting? (docs/accuracy.md)

For iClone / Character Creator BVH files (``CC_Base_*`` joints, the ``cmu_iclone``
folder of the shared data): per foot, the cosine between the big-toe-minus-little-toe
direction and the direction from the foot towards the pelvis, both taken across the
foot's long axis (foot -> toe base). On a foot a person stands or steps on the big toe
is on the inner side, so the cosine is positive; a negative mean means the source
animation rolls the foot over.

    PYTHONPATH=. python research/source_foot_roll.py FILE.bvh... [--max-frames 150]
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np
from pymotion.io.bvh import BVH
from pymotion.ops.skeleton_np import fk


def _across(v: np.ndarray, axis: np.ndarray) -> np.ndarray:
    """``v`` without its component along ``axis`` (both (F, 3))."""
    return v - (v * axis).sum(1, keepdims=True) * axis / np.maximum((axis * axis).sum(1, keepdims=True), 1e-12)


def foot_roll(path: str, max_frames: int) -> dict[str, float]:
    """Mean cosine per foot (``L``, ``R``) over the first ``max_frames`` frames."""
    bvh = BVH()
    bvh.load(path)
    rot, pos, parents, offsets, _, _ = bvh.get_data()
    names = list(bvh.data["names"])
    world, _ = fk(rot[:max_frames], pos[:max_frames, 0], offsets, parents)
    out = {}
    for side in "LR":
        try:
            at = {n: world[:, names.index(f"CC_Base_{side}_{n}")] for n in ("Foot", "ToeBase", "BigToe1", "PinkyToe1")}
        except ValueError as exc:
            raise SystemExit(f"{path}: not an iClone / Character Creator rig ({exc})") from None
        axis = at["ToeBase"] - at["Foot"]
        inward = _across(world[:, names.index("CC_Base_Pelvis")] - at["Foot"], axis)
        lateral = _across(at["BigToe1"] - at["PinkyToe1"], axis)
        cos = (inward * lateral).sum(1) / np.maximum(
            np.linalg.norm(inward, axis=1) * np.linalg.norm(lateral, axis=1), 1e-12
        )
        out[side] = float(cos.mean())
    return out


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("files", nargs="+")
    ap.add_argument("--max-frames", type=int, default=150)
    args = ap.parse_args()
    print(f"{'file':<16} {'left':>6} {'right':>6}  (mean cosine: big toe towards the body > 0)")
    for f in args.files:
        r = foot_roll(f, args.max_frames)
        print(f"{Path(f).stem:<16} {r['L']:6.2f} {r['R']:6.2f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
