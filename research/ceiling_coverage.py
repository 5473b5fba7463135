"""Is the VAE's ceiling on another lab's motion a matter of coverage? The ceiling (encode
the true pose, decode it) per frame, against how far that pose is from the training data.

    .venv/bin/python research/ceiling_coverage.py --data prepared FILE... [--compare FILE...]
        [--max-frames 600] [--stride 4] [--train-stride 8] [--groups hdm05] [--json OUT.json]

For every ``--stride``-th frame of each file (and of each ``--compare`` file, e.g. the
validation files), the VAE ceiling's mean joint position error (cm, as ``pos_cm``) and
the pose's **coverage distance**: its distance (cm; root-relative, heading-aligned joint
positions on the canonical skeleton, ``engine.authoring.pose_reference``) to the nearest
pose of the training split of ``--data`` (every ``--train-stride``-th frame, mirrors
included as prepared). Prints the ceiling binned by coverage distance for both sets:
where both sets have the same ceiling at the same distance, what separates their means
is how much of each lies far from the training poses. ``--groups hdm05`` adds a table
per HDM05 motion class (the file name's part between the performer and the take
number).
"""

from __future__ import annotations

import argparse
import json
import re
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from engine import skeleton as sk  # noqa: E402

BINS = (0.0, 3.0, 4.5, 6.0, 8.0, 11.0, 15.0, np.inf)


def training_poses(data: Path, stride: int) -> np.ndarray:
    """Aligned training poses ``(N, 21, 3)`` float32: every ``stride``-th frame of the
    ``train`` split's shards (their mirrored copies included, as prepared)."""
    from engine.authoring.pose_reference import ReferenceSet
    from engine.training.data import read_manifest

    entries = [e for e in read_manifest(data)["files"] if e["split"] == "train"]
    pairs = [(str(i), np.load(data / e["shard"])["local_rot"]) for i, e in enumerate(entries)]
    return ReferenceSet.from_rotations(pairs, sk.REST_OFFSETS, stride, mirror=False).poses


def frame_rows(files: list[str], poses: np.ndarray, max_frames: int, stride: int) -> list[dict]:
    """Per file: frame ceiling errors (cm) and coverage distances (cm)."""
    from engine.authoring.pose_reference import aligned, pose_distances
    from engine.kinematics.fk import fk
    from engine.methods import get_method, run_method
    from engine.motion.retarget import load_motion
    from engine.tracking import simulate

    method = get_method("autoencoder")
    out = []
    for f in files:
        motion = load_motion(f, max_frames=max_frames)
        rec, _ = run_method(method, simulate(motion, "6"), motion.skeleton, progress=False, reference=motion)
        gt_p = fk(motion.local_rot, motion.root_pos, motion.skeleton.offsets)[0][::stride]
        rec_p = fk(rec.local_rot, rec.root_pos, motion.skeleton.offsets)[0][::stride]
        joint_err = 100.0 * np.linalg.norm(gt_p - rec_p, axis=-1)
        err = joint_err.mean(1)
        zero = np.zeros((len(err), 3))
        canon = fk(motion.local_rot[::stride], zero, sk.REST_OFFSETS)[0]
        canon_rec = fk(rec.local_rot[::stride], zero, sk.REST_OFFSETS)[0]
        q = aligned(canon).astype(np.float32)
        cover = np.concatenate([pose_distances(q[i : i + 128], poses).min(1) for i in range(0, len(q), 128)])
        out.append(
            {
                "file": f,
                "err_cm": err.tolist(),
                "cover_cm": (100.0 * cover).tolist(),
                "canon_err_cm": (100.0 * np.linalg.norm(canon - canon_rec, axis=-1).mean(1)).tolist(),
                "joint_err_cm": joint_err.mean(0).tolist(),
                "frames": len(err),
            }
        )
    return out


def binned(rows: list[dict]) -> list[tuple[float, float, int]]:
    """Per coverage bin: (share of frames %, mean ceiling cm, frames)."""
    err = np.concatenate([r["err_cm"] for r in rows])
    cov = np.concatenate([r["cover_cm"] for r in rows])
    res = []
    for lo, hi in zip(BINS[:-1], BINS[1:]):
        m = (cov >= lo) & (cov < hi)
        res.append((100.0 * m.mean(), float(err[m].mean()) if m.any() else float("nan"), int(m.sum())))
    return res


def hdm05_class(path: str) -> str:
    m = re.match(r"HDM_[a-z]+_(.+?)_\d+_\d+$", Path(path).stem)
    return m.group(1) if m else Path(path).stem


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("files", nargs="+")
    ap.add_argument("--data", type=Path, default=Path("prepared"))
    ap.add_argument("--compare", nargs="*", default=[])
    ap.add_argument("--max-frames", type=int, default=600)
    ap.add_argument("--stride", type=int, default=4)
    ap.add_argument("--train-stride", type=int, default=8)
    ap.add_argument("--groups", choices=("none", "hdm05"), default="none")
    ap.add_argument("--json", type=Path)
    args = ap.parse_args()

    poses = training_poses(args.data, args.train_stride)
    print(f"training poses: {len(poses)} (every {args.train_stride}th frame of {args.data}'s train split)")
    sets = {"files": frame_rows(args.files, poses, args.max_frames, args.stride)}
    if args.compare:
        sets["compare"] = frame_rows(args.compare, poses, args.max_frames, args.stride)
    for name, rows in sets.items():
        err = np.concatenate([r["err_cm"] for r in rows])
        cov = np.concatenate([r["cover_cm"] for r in rows])
        print(
            f"\n{name}: {len(rows)} clips, {len(err)} frames; ceiling {err.mean():.2f} cm; "
            f"coverage distance median {np.median(cov):.1f} cm, p90 {np.percentile(cov, 90):.1f}; "
            f"Pearson r(coverage, ceiling) {np.corrcoef(cov, err)[0, 1]:.2f}; on the canonical skeleton "
            f"{np.concatenate([r['canon_err_cm'] for r in rows]).mean():.2f} cm"
        )
        print(f"{'coverage cm':>14} {'frames %':>9} {'ceiling cm':>11} {'frames':>7}")
        for (lo, hi), (share, mean, n) in zip(zip(BINS[:-1], BINS[1:]), binned(rows)):
            print(f"{lo:6.1f}-{hi:<7.1f} {share:9.1f} {mean:11.2f} {n:7d}")
    if len(sets) == 2:
        a, b = (binned(sets[k]) for k in ("files", "compare"))
        mixed = sum(sa / 100.0 * mb for (sa, _, _), (_, mb, _) in zip(a, b) if not np.isnan(mb))
        print(f"\nthe compare set's ceiling per bin, weighted by the files' coverage: {mixed:.2f} cm")
        w = {k: np.array([r["frames"] for r in v], float) for k, v in sets.items()}
        j = {k: (np.array([r["joint_err_cm"] for r in v]) * w[k][:, None]).sum(0) / w[k].sum() for k, v in sets.items()}
        print(f"{'joint':<11} {'files cm':>8} {'compare cm':>10}")
        for i in np.argsort(-(j["files"] - j["compare"])):
            print(f"{sk.JOINT_NAMES[i]:<11} {j['files'][i]:8.2f} {j['compare'][i]:10.2f}")
    if args.groups == "hdm05":
        groups: dict[str, list[dict]] = {}
        for r in sets["files"]:
            groups.setdefault(hdm05_class(r["file"]), []).append(r)
        print(f"\n{'class':<34} {'clips':>5} {'frames':>6} {'ceiling cm':>10} {'coverage cm':>11}")
        order = sorted(groups, key=lambda g: -np.mean(np.concatenate([r["err_cm"] for r in groups[g]])))
        for g in order:
            e = np.concatenate([r["err_cm"] for r in groups[g]])
            c = np.concatenate([r["cover_cm"] for r in groups[g]])
            print(f"{g:<34} {len(groups[g]):5d} {len(e):6d} {e.mean():10.2f} {np.median(c):11.1f}")
    if args.json:
        args.json.write_text(json.dumps(sets))
    return 0


if __name__ == "__main__":
    sys.exit(main())
