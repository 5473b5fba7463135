"""How far a clip's tracker readings are from the pose bank's training frames.

For every frame of each clip (the true joints' readings, as simulated trackers give
them), the standardised feature distance (engine/solver/tracker_prior.py) to the ``K``
nearest bank frames, as the root mean square per feature dimension, averaged over the
``K``. Prints the 10th, 50th, 90th and 99th percentiles per group of files: a group of
held-out clips whose distances match the validation files' looks no more unusual to the
bank than they do (docs/accuracy.md, "Held-out clips, session 10").

    PYTHONPATH=. python research/bank_distance.py --joints root,upperneck,lwrist,rwrist \\
        --group VAL1.bvh VAL2.bvh ... --group HELD1.bvh ... [--max-frames 600] [--k 24]
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np
import torch

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from engine import skeleton as sk  # noqa: E402
from engine.solver.tracker_prior import ANCHORS, LAG, default_bank, features  # noqa: E402


def distances(bank, joints: tuple[str, ...], motion, k: int) -> np.ndarray:
    """Per-frame RMS standardised distance ``(F,)`` to the ``k`` nearest bank frames."""
    from engine.kinematics.fk import fk

    idx = bank._index(joints)
    cols = [sk.JOINT_INDEX[j] for j in joints]
    a = next(i for i, j in enumerate(joints) if j in ANCHORS)
    p, r = fk(motion.local_rot, motion.root_pos, motion.skeleton.offsets)
    pos, rot = p[:, cols], r[:, cols]
    prev = np.concatenate((np.repeat(pos[:1, a], LAG, 0), pos[:-LAG, a]))[: len(pos)]
    x = features(pos, rot, a, prev)
    q = torch.as_tensor((x - idx.mean) / idx.std, dtype=torch.float32)
    d2 = idx.norms[None] - 2.0 * q @ idx.table.T + (q * q).sum(1)[:, None]
    near = d2.topk(k, largest=False).values.clamp(min=0.0)
    return np.sqrt(near.mean(1).numpy() / x.shape[1])


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--joints", default="root,upperneck,lwrist,rwrist", help="bank joints the trackers sit on")
    ap.add_argument("--group", nargs="+", action="append", required=True, help="BVH files of one group")
    ap.add_argument("--max-frames", type=int, default=600)
    ap.add_argument("--k", type=int, default=24)
    args = ap.parse_args()

    from engine.motion.retarget import load_motion

    bank = default_bank()
    if bank is None:
        print("no pose bank for the shipped VAE (assets/models/pose_bank.npz)", file=sys.stderr)
        return 2
    joints = tuple(args.joints.split(","))
    for files in args.group:
        d = np.concatenate([distances(bank, joints, load_motion(f, max_frames=args.max_frames), args.k) for f in files])
        pct = " / ".join(f"{v:.2f}" for v in np.percentile(d, [10, 50, 90, 99]))
        print(f"{len(files)} files, {len(d)} frames: percentiles 10/50/90/99 {pct}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
