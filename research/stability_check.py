"""Head-and-hands stability: pelvis flips, divergence and sensitivity to tiny input changes.

    PYTHONPATH=. python research/stability_check.py [FILE.bvh ...] [--sensors 3-head-hands]
        [--method dragposer] [--modes realtime offline] [--max-frames 300] [--noise 1e-6]
        [--seeds 1 2] [--set KEY=VALUE ...] [--json OUT] [--markdown OUT.md]

For every file (default: the validation files, ``dragposer-studio data list --split val``)
and mode, the method (DragPoser by default) reconstructs the clip from clean simulated
trackers and again with every tracker position moved by N(0, ``--noise``) metres (one run
per seed). Per run it reports the position error (cm), the worst frame's error, the worst
angle between the reconstructed and the true pelvis orientation over the clip
(``pelvis``: lean and turn together) and the worst angle about the vertical between their
facing directions (``heading``, :func:`facing`: a pelvis turned round shows as > 90 deg
whatever either leans); per file, how far the perturbed runs' mean errors are from the
clean run's (``spread``) and how far apart the perturbed and clean reconstructions are
(``apart``: mean joint distance over the clip, cm). A stable solver gives about zero for
both.

Flags in the output: ``FLIP`` (heading > 90 deg on some frame), ``DIVERGED`` (a frame's
error above 50 cm or non-finite), ``UNSTABLE`` (spread above 0.5 cm). ``FLIP`` reads the
heading only, not the total angle (``pelvis``), which also counts the lean that head
and hands barely show (docs/optimizer.md, "Stability with head and hands").
"""

from __future__ import annotations

import argparse
import json
import math
import subprocess
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from engine.atomic import write_text  # noqa: E402
from engine.solver.settings import MODES  # noqa: E402

FLIP_DEG = 90.0
DIVERGED_CM = 50.0
UNSTABLE_CM = 0.5


def _val_files() -> list[str]:
    cli = str(Path(sys.executable).parent / "dragposer-studio")
    return subprocess.run(
        [cli, "data", "list", "--split", "val"], capture_output=True, text=True, check=True, cwd=ROOT
    ).stdout.split()


def pelvis_angle_deg(gt_q: np.ndarray, rec_q: np.ndarray) -> np.ndarray:
    """Angle (deg) between two root orientations per frame, ``(F, 4)`` unit quaternions."""
    d = np.abs(np.einsum("fi,fi->f", gt_q, rec_q))
    return np.degrees(2.0 * np.arccos(np.clip(d, 0.0, 1.0)))


def facing(q: np.ndarray) -> np.ndarray:
    """Horizontal facing direction ``(F, 2)`` of root orientations ``(F, 4)``: the horizontal
    part of the rotated forward axis (-Y at rest) plus that of the rotated left axis (+X)
    turned a quarter round, so a pelvis that leans forward (forward axis steep) or sideways
    (left axis steep) still gives its facing (the hip line's, or the belly's)."""
    from engine.kinematics import quaternion as Q

    n = q.shape[:-1]
    fwd = Q.rotate(q, np.broadcast_to([0.0, -1.0, 0.0], n + (3,)))
    left = Q.rotate(q, np.broadcast_to([1.0, 0.0, 0.0], n + (3,)))
    return np.stack((fwd[..., 0] + left[..., 1], fwd[..., 1] - left[..., 0]), axis=-1)


def heading_angle_deg(gt_q: np.ndarray, rec_q: np.ndarray) -> np.ndarray:
    """Angle (deg, 0-180) about the vertical between the :func:`facing` of two root
    orientations per frame, ``(F, 4)``: the pelvis turned away from the truth's, whatever
    either leans (a lean the trackers of head and hands barely show is not a flip)."""
    a, b = facing(gt_q), facing(rec_q)
    cross = a[..., 0] * b[..., 1] - a[..., 1] * b[..., 0]
    return np.degrees(np.abs(np.arctan2(cross, np.einsum("...i,...i", a, b))))


def run_once(
    motion,
    preset: str,
    mode: str,
    noise: float,
    seed: int,
    settings: dict | None = None,
    method_name: str = "dragposer",
) -> dict:
    """One reconstruction; its error summary (cm, deg) and its joint positions ``rec_pos (F, 22, 3)``
    (``settings``: optimizer settings applied with ``configure``, as ``--set`` does)."""
    from engine.kinematics.fk import fk
    from engine.methods import get_method, run_method
    from engine.tracking import simulate

    tracking = simulate(motion, preset, noise_pos_m=noise, seed=seed)
    method = get_method(method_name, mode=mode)
    if settings:
        method.configure(**settings)
    rec, _ = run_method(method, tracking, motion.skeleton, progress=False, light=True, reference=motion)
    gt_pos, _ = fk(motion.local_rot, motion.root_pos, motion.skeleton.offsets)
    rec_pos, _ = fk(rec.local_rot, rec.root_pos, motion.skeleton.offsets)
    err = np.linalg.norm(gt_pos - rec_pos, axis=-1).mean(-1) * 100.0  # (F,) cm
    angle = pelvis_angle_deg(motion.local_rot[:, 0], rec.local_rot[:, 0])
    turn = heading_angle_deg(motion.local_rot[:, 0], rec.local_rot[:, 0])
    finite = bool(np.isfinite(err).all())
    return {
        "pos_cm": float(np.nanmean(err)),
        "worst_frame_cm": float(np.nanmax(err)) if finite else math.inf,
        "pelvis_max_deg": float(np.nanmax(angle)),
        "heading_max_deg": float(np.nanmax(turn)),
        "finite": finite,
        "rec_pos": rec_pos,
    }


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("files", nargs="*", help="BVH files (default: the validation files)")
    ap.add_argument("--sensors", default="3-head-hands")
    ap.add_argument("--method", default="dragposer", help="dragposer (default), ik or autoencoder")
    ap.add_argument("--modes", nargs="+", default=list(MODES), choices=MODES)
    ap.add_argument("--max-frames", type=int, default=300, help="first N frames of each file (0: whole files)")
    ap.add_argument("--noise", type=float, default=1e-6, help="tracker position perturbation, metres (default 1e-6)")
    ap.add_argument("--seeds", type=int, nargs="+", default=[1, 2])
    ap.add_argument(
        "--set",
        action="append",
        default=[],
        metavar="KEY=VALUE",
        help="optimizer setting, repeatable (as for evaluate)",
    )
    ap.add_argument("--json", type=Path)
    ap.add_argument("--markdown", type=Path, help="also write the table as Markdown")
    args = ap.parse_args()

    from engine.config import parse_overrides
    from engine.motion.retarget import load_motion
    from engine.solver import OptimizerSettings

    settings = parse_overrides(OptimizerSettings, args.set) if args.set else {}
    files = args.files or _val_files()
    report, flags_total, rows = [], 0, []
    head = (
        "file",
        "mode",
        "clean cm",
        "worst frame cm",
        "pelvis max deg",
        "heading max deg",
        "perturbed cm",
        "spread cm",
        "apart cm",
        "flags",
    )
    print(
        f"{head[0]:<18} {head[1]:<9} {'clean cm':>9} {'worst':>7} {'pelvis':>7} {'heading':>7} "
        f"{'perturbed cm':>14} {'spread':>7} {'apart':>7}  flags"
    )
    for path in files:
        motion = load_motion(path, max_frames=args.max_frames or None)
        for mode in args.modes:
            clean = run_once(motion, args.sensors, mode, 0.0, 0, settings, args.method)
            noisy = [run_once(motion, args.sensors, mode, args.noise, s, settings, args.method) for s in args.seeds]
            runs = [clean, *noisy]
            spread = max(abs(r["pos_cm"] - clean["pos_cm"]) for r in noisy)
            # how far the perturbed reconstructions are from the clean one (mean over frames and joints)
            apart = max(float(np.linalg.norm(r["rec_pos"] - clean["rec_pos"], axis=-1).mean()) * 100.0 for r in noisy)
            flags = []
            if any(r["heading_max_deg"] > FLIP_DEG for r in runs):
                flags.append("FLIP")
            if any(not r["finite"] or r["worst_frame_cm"] > DIVERGED_CM for r in runs):
                flags.append("DIVERGED")
            if spread > UNSTABLE_CM:
                flags.append("UNSTABLE")
            flags_total += len(flags)
            name = f"{Path(path).parent.name}/{Path(path).stem}"
            row = (
                name,
                mode,
                f"{clean['pos_cm']:.2f}",
                f"{max(r['worst_frame_cm'] for r in runs):.1f}",
                f"{max(r['pelvis_max_deg'] for r in runs):.1f}",
                f"{max(r['heading_max_deg'] for r in runs):.1f}",
                " ".join(f"{r['pos_cm']:.2f}" for r in noisy),
                f"{spread:.3f}",
                f"{apart:.3f}",
                " ".join(flags),
            )
            rows.append(row)
            print(
                f"{row[0]:<18} {row[1]:<9} {row[2]:>9} {row[3]:>7} {row[4]:>7} {row[5]:>7} {row[6]:>14} "
                f"{row[7]:>7} {row[8]:>7}  {row[9]}",
                flush=True,
            )
            strip = lambda r: {k: v for k, v in r.items() if k != "rec_pos"}  # noqa: E731
            report.append(
                {
                    "file": path,
                    "mode": mode,
                    "clean": strip(clean),
                    "perturbed": [strip(r) for r in noisy],
                    "spread_cm": spread,
                    "apart_cm": apart,
                    "flags": flags,
                }
            )
    summary = (
        f"{flags_total} flag(s) over {len(report)} runs (method {args.method}, preset {args.sensors}, "
        f"{args.max_frames or 'all'} frames, noise {args.noise:g} m, seeds {' '.join(map(str, args.seeds))}"
        + (f", {' '.join(args.set)}" if args.set else "")
        + ")"
    )
    print(summary)
    if args.json:
        write_text(
            args.json,
            json.dumps(
                {
                    "method": args.method,
                    "sensors": args.sensors,
                    "max_frames": args.max_frames,
                    "noise_m": args.noise,
                    "settings": settings,
                    "runs": report,
                },
                indent=1,
            ),
        )
    if args.markdown:
        lines = ["| " + " | ".join(head) + " |", "|---|---|" + "---:|" * 7 + "---|"]
        lines += ["| " + " | ".join(r) + " |" for r in rows]
        write_text(args.markdown, "\n".join(lines) + "\n\n" + summary + "\n")
    return 1 if flags_total else 0


if __name__ == "__main__":
    sys.exit(main())
