"""Head-and-hands stability: pelvis flips, divergence and sensitivity to tiny input changes.

    PYTHONPATH=. python scripts/stability_check.py [FILE.bvh ...] [--sensors 3-head-hands]
        [--modes realtime offline] [--max-frames 300] [--noise 1e-6] [--seeds 1 2] [--json OUT]

For every file (default: the validation files, ``dragposer-studio data list --split val``)
and mode, DragPoser reconstructs the clip from clean simulated trackers and again with
every tracker position moved by N(0, ``--noise``) metres (one run per seed). Per run it
reports the position error (cm), the worst frame's error, and the worst angle between the
reconstructed and the true pelvis orientation over the clip (a pelvis that turned
upside down or faces backwards shows as > 90 deg); per file, how far the perturbed runs'
mean errors are from the clean run's (``spread``: a stable solver gives about zero).

Flags in the output: ``FLIP`` (pelvis angle > 90 deg on some frame), ``DIVERGED`` (a
frame's error above 50 cm or non-finite), ``UNSTABLE`` (spread above 0.5 cm).
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

FLIP_DEG = 90.0
DIVERGED_CM = 50.0
UNSTABLE_CM = 0.5


def _val_files() -> list[str]:
    cli = str(Path(sys.executable).parent / "dragposer-studio")
    return subprocess.run([cli, "data", "list", "--split", "val"], capture_output=True, text=True, check=True,
                          cwd=ROOT).stdout.split()  # fmt: skip


def pelvis_angle_deg(gt_q: np.ndarray, rec_q: np.ndarray) -> np.ndarray:
    """Angle (deg) between two root orientations per frame, ``(F, 4)`` unit quaternions."""
    d = np.abs(np.einsum("fi,fi->f", gt_q, rec_q))
    return np.degrees(2.0 * np.arccos(np.clip(d, 0.0, 1.0)))


def run_once(motion, preset: str, mode: str, noise: float, seed: int) -> dict:
    """One reconstruction; its error summary (cm, deg)."""
    from engine.kinematics.fk import fk
    from engine.methods import get_method, run_method
    from engine.tracking import simulate

    tracking = simulate(motion, preset, noise_pos_m=noise, seed=seed)
    method = get_method("dragposer", mode=mode)
    rec, _ = run_method(method, tracking, motion.skeleton, progress=False, light=True)
    gt_pos, _ = fk(motion.local_rot, motion.root_pos, motion.skeleton.offsets)
    rec_pos, _ = fk(rec.local_rot, rec.root_pos, motion.skeleton.offsets)
    err = np.linalg.norm(gt_pos - rec_pos, axis=-1).mean(-1) * 100.0  # (F,) cm
    angle = pelvis_angle_deg(motion.local_rot[:, 0], rec.local_rot[:, 0])
    finite = bool(np.isfinite(err).all())
    return {"pos_cm": float(np.nanmean(err)), "worst_frame_cm": float(np.nanmax(err)) if finite else math.inf,
            "pelvis_max_deg": float(np.nanmax(angle)), "finite": finite}  # fmt: skip


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("files", nargs="*")
    ap.add_argument("--sensors", default="3-head-hands")
    ap.add_argument("--modes", nargs="+", default=["realtime", "offline"], choices=("realtime", "offline"))
    ap.add_argument("--max-frames", type=int, default=300)
    ap.add_argument("--noise", type=float, default=1e-6, help="tracker position perturbation, metres (default 1e-6)")
    ap.add_argument("--seeds", type=int, nargs="+", default=[1, 2])
    ap.add_argument("--json", type=Path)
    args = ap.parse_args()

    from engine.retarget import load_motion

    files = args.files or _val_files()
    report, flags_total = [], 0
    print(f"{'file':<18} {'mode':<9} {'clean cm':>9} {'worst':>7} {'pelvis':>7} {'perturbed cm':>18} "
          f"{'spread':>7}  flags")  # fmt: skip
    for path in files:
        motion = load_motion(path, max_frames=args.max_frames)
        for mode in args.modes:
            clean = run_once(motion, args.sensors, mode, 0.0, 0)
            noisy = [run_once(motion, args.sensors, mode, args.noise, s) for s in args.seeds]
            runs = [clean, *noisy]
            spread = max(abs(r["pos_cm"] - clean["pos_cm"]) for r in noisy)
            flags = []
            if any(r["pelvis_max_deg"] > FLIP_DEG for r in runs):
                flags.append("FLIP")
            if any(not r["finite"] or r["worst_frame_cm"] > DIVERGED_CM for r in runs):
                flags.append("DIVERGED")
            if spread > UNSTABLE_CM:
                flags.append("UNSTABLE")
            flags_total += len(flags)
            name = f"{Path(path).parent.name}/{Path(path).stem}"
            perturbed = " ".join(f"{r['pos_cm']:.2f}" for r in noisy)
            print(f"{name:<18} {mode:<9} {clean['pos_cm']:9.2f} {max(r['worst_frame_cm'] for r in runs):7.1f} "
                  f"{max(r['pelvis_max_deg'] for r in runs):7.1f} "
                  f"{perturbed:>18} {spread:7.3f}  {' '.join(flags)}",
                  flush=True)  # fmt: skip
            report.append({"file": path, "mode": mode, "clean": clean, "perturbed": noisy, "spread_cm": spread,
                           "flags": flags})  # fmt: skip
    print(f"{flags_total} flag(s) over {len(report)} runs (preset {args.sensors}, {args.max_frames} frames, "
          f"noise {args.noise:g} m)")  # fmt: skip
    if args.json:
        write_text(args.json, json.dumps({"sensors": args.sensors, "max_frames": args.max_frames,
                                          "noise_m": args.noise, "runs": report}, indent=1))  # fmt: skip
    return 1 if flags_total else 0


if __name__ == "__main__":
    sys.exit(main())
