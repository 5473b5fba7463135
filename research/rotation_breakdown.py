"""Per-joint rotation and position error of a method on simulated trackers (where the Rot
and Pos figures come from).

    .venv/bin/python research/rotation_breakdown.py FILE... [--method dragposer] [--sensors 6]
        [--mode realtime] [--max-frames 300] [--set KEY=VALUE ...] [--vae V.pt --predictor P.pt]
        [--twist]

Prints, per joint, the mean geodesic error of its local rotation (degrees, as
``rot_deg`` of ``evaluate``) and, with ``--twist``, how much of it is twist about the
bone to the joint's child (swing-twist split of the error rotation), the joint's world
position error (cm, as ``pos_cm``), then the means and the share of the position error
in the legs (hips, knees, ankles, toes).
``--method autoencoder`` gives the VAE's ceiling (the true pose encoded and decoded).

``--per-file`` adds a table per file: the mean error and, for the joints named by
``--joints``, the error and the mean angle of the ground truth's and the reconstruction's
local rotation from identity (``truth/reconstruction``). Trackers do not say which of two
rotation conventions a rig uses at joints they cannot see (e.g. the spine: the iClone
rig's upper back sits about 80 degrees from identity, the Daz rig has none), so a large
error with both angles far apart there is the solver choosing the other convention.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from engine import skeleton as sk  # noqa: E402
from engine.kinematics import quaternion as Q  # noqa: E402


def twist_angle(err: np.ndarray, axis: np.ndarray) -> np.ndarray:
    """Twist part (degrees) of error rotations ``(..., 4)`` about unit ``axis (3,)``."""
    proj = (err[..., 1:] @ axis)[..., None] * axis
    tw = np.concatenate((err[..., :1], proj), axis=-1)
    n = np.linalg.norm(tw, axis=-1)
    return np.degrees(2.0 * np.arctan2(np.linalg.norm(proj, axis=-1), np.abs(err[..., 0]) + 1e-12)) * (n > 1e-9)


def per_file_row(gt: np.ndarray, rec: np.ndarray, err_deg: np.ndarray, joints: list[int]):
    """``(mean error, [(error, truth angle, reconstruction angle) per joint])`` in degrees
    for one file: ``gt``/``rec`` local rotations ``(F, 22, 4)``, ``err_deg (F, 22)``; the
    angles are each rotation's mean angle from identity."""
    ident = np.array([1.0, 0.0, 0.0, 0.0])
    a_gt, a_rec = np.degrees(Q.angle(gt, ident)), np.degrees(Q.angle(rec, ident))
    return float(err_deg.mean()), [
        (float(err_deg[:, j].mean()), float(a_gt[:, j].mean()), float(a_rec[:, j].mean())) for j in joints
    ]


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("files", nargs="+")
    ap.add_argument("--method", default="dragposer")
    ap.add_argument("--sensors", default="6")
    ap.add_argument("--mode", default="realtime")
    ap.add_argument("--max-frames", type=int, default=300)
    ap.add_argument("--set", action="append", default=[])
    ap.add_argument("--vae")
    ap.add_argument("--predictor")
    ap.add_argument("--twist", action="store_true")
    ap.add_argument("--per-file", action="store_true")
    ap.add_argument("--joints", default="lowerback,upperback,chest,lshoulder,rshoulder,lwrist,rwrist")
    args = ap.parse_args()
    joints = [sk.JOINT_INDEX[n] for n in args.joints.split(",")]

    from engine.methods import get_method, run_method
    from engine.motion.retarget import load_motion
    from engine.tracking import simulate

    kw = {"mode": args.mode}
    if args.vae:
        kw["vae_path"] = args.vae
    if args.predictor:
        kw["predictor_path"] = args.predictor
    method = get_method(args.method, **kw)
    if args.set:
        from engine.config import parse_overrides
        from engine.solver import OptimizerSettings

        method.configure(**parse_overrides(OptimizerSettings, args.set))
    from engine.kinematics.fk import fk

    errs, twists, pos_errs, rows = [], [], [], []
    children = {j: sk.children(j) for j in range(sk.NUM_JOINTS)}
    for f in args.files:
        motion = load_motion(f, max_frames=args.max_frames)
        rec, _ = run_method(method, simulate(motion, args.sensors), motion.skeleton, progress=False, reference=motion)
        gt, out = Q.normalize(motion.local_rot), Q.normalize(rec.local_rot)
        errs.append(np.degrees(Q.angle(gt, out)))
        gt_p, _ = fk(motion.local_rot, motion.root_pos, motion.skeleton.offsets)
        rec_p, _ = fk(rec.local_rot, rec.root_pos, motion.skeleton.offsets)
        pos_errs.append(100.0 * np.linalg.norm(gt_p - rec_p, axis=-1))
        err = Q.mul(Q.conjugate(gt), out)  # error in the joint's own frame
        tw = np.zeros(errs[-1].shape)
        for j in range(sk.NUM_JOINTS):
            if children[j]:
                axis = motion.skeleton.offsets[children[j][0]]
                tw[:, j] = twist_angle(err[:, j], axis / np.linalg.norm(axis))
        twists.append(tw)
        rows.append(
            (
                Path(f).stem if len(Path(f).parts) < 2 else "/".join(Path(f).parts[-2:]),
                per_file_row(gt, out, errs[-1], joints),
            )
        )
    e, t = np.concatenate(errs).mean(0), np.concatenate(twists).mean(0)
    p = np.concatenate(pos_errs).mean(0)
    print(f"{'joint':<11} {'rot deg':>8} {'pos cm':>7}" + (f" {'twist deg':>9}" if args.twist else ""))
    for j, name in enumerate(sk.JOINT_NAMES):
        print(f"{name:<11} {e[j]:8.1f} {p[j]:7.2f}" + (f" {t[j]:9.1f}" if args.twist and children[j] else ""))
    legs = [sk.JOINT_INDEX[n] for n in ("lhip", "lknee", "lankle", "ltoe", "rhip", "rknee", "rankle", "rtoe")]
    print(f"{'mean':<11} {e.mean():8.2f} {p.mean():7.2f}")
    print(
        f"legs: {100.0 * p[legs].sum() / p.sum():.0f} % of the position error ({len(legs)} of {sk.NUM_JOINTS} joints)"
    )
    if args.per_file:
        names = [sk.JOINT_NAMES[j] for j in joints]
        print("\nper file: mean rot deg; per joint: error deg (truth/reconstruction angle from identity)")
        print(f"{'file':<22} {'mean':>5} " + " ".join(f"{n:>15}" for n in names))
        for name, (mean, cols) in rows:
            print(f"{name:<22} {mean:5.1f} " + " ".join(f"{e:5.1f} ({a:3.0f}/{b:3.0f})" for e, a, b in cols))
    return 0


if __name__ == "__main__":
    sys.exit(main())
