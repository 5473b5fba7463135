"""Does the prior readout separate good frames from bad ones? Per sensor preset, the
correlation between each frame's distance to the nearest training latent and its position
error, on the validation files (docs/latent.md, "Does the readout find bad frames?").

Each validation file (``engine.authoring.pose_reference.VALIDATION_FILES``) is
reconstructed with DragPoser (shipped models, realtime, simulated trackers, seed 0) over
its first ``--max-frames`` frames and traced (:func:`engine.latent.trace.trace_clip`).
Printed per preset: frames, mean Pos error, the Pearson and Spearman correlations over
all frames pooled and their median over the files, the share of frames flagged and the
mean Pos error of the frames in the top decile of ``nearest`` against the rest.

    PYTHONPATH=. python research/latent_correlation.py --presets 6 4 3-head-hands --max-frames 200 --json OUT.json
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from engine.latent.probe import LatentProbe  # noqa: E402
from engine.latent.trace import trace_clip  # noqa: E402


def _corr(x: np.ndarray, y: np.ndarray) -> tuple[float, float]:
    """Pearson and Spearman correlation of ``x`` and ``y``."""
    rank = lambda a: np.argsort(np.argsort(a)).astype(float)  # noqa: E731
    return float(np.corrcoef(x, y)[0, 1]), float(np.corrcoef(rank(x), rank(y))[0, 1])


def main() -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--presets", nargs="+", default=["6", "4", "3-head-hands"])
    p.add_argument("--max-frames", type=int, default=200)
    p.add_argument("--json", type=Path)
    p.add_argument(
        "--mocap",
        type=Path,
        default=Path(__file__).resolve().parent.parent.parent / "shared" / "data" / "mocap",
        help="folder holding the validation files (default: ../shared/data/mocap)",
    )
    args = p.parse_args()
    from engine.authoring.pose_reference import validation_files
    from engine.methods import get_method
    from engine.motion.retarget import load_motion
    from engine.tracking import simulate

    probe = LatentProbe.shipped()
    method = get_method("dragposer")
    files = validation_files(args.mocap)
    motions = [load_motion(f).slice(0, args.max_frames) for f in files]
    out: dict = {"max_frames": args.max_frames, "files": [str(f) for f in files], "presets": {}}
    print(
        "| preset | frames | Pos cm | r pooled | rho pooled | r median per file | flagged | Pos cm, top 10 % nearest / rest |"
    )
    print("|---|---:|---:|---:|---:|---:|---:|---|")
    for preset in args.presets:
        t0 = time.perf_counter()
        near, pos, flags, per_file = [], [], [], []
        for f, motion in zip(files, motions):
            trace = trace_clip(method, simulate(motion, preset), motion, probe)
            near.append(trace.column("nearest"))
            pos.append(trace.pos_cm)
            flags.append(trace.column("flagged"))
            per_file.append({"file": f.name, **trace.correlation("nearest"), "pos_cm": float(trace.pos_cm.mean())})
        x, y = np.concatenate(near), np.concatenate(pos)
        r, rho = _corr(x, y)
        top = x >= np.quantile(x, 0.9)
        row = {
            "frames": int(len(x)),
            "pos_cm": float(y.mean()),
            "pearson": r,
            "spearman": rho,
            "pearson_median_per_file": float(np.nanmedian([d["pearson"] for d in per_file])),
            "flagged_share": float(np.concatenate(flags).mean()),
            "pos_cm_top_decile": float(y[top].mean()),
            "pos_cm_rest": float(y[~top].mean()),
            "per_file": per_file,
            "seconds": time.perf_counter() - t0,
        }
        out["presets"][preset] = row
        print(
            f"| {preset} | {row['frames']} | {row['pos_cm']:.2f} | {r:.2f} | {rho:.2f} | "
            f"{row['pearson_median_per_file']:.2f} | {100 * row['flagged_share']:.1f} % | "
            f"{row['pos_cm_top_decile']:.2f} / {row['pos_cm_rest']:.2f} |",
            flush=True,
        )
    if args.json:
        from engine.atomic import write_text

        write_text(args.json, json.dumps(out, indent=1) + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
