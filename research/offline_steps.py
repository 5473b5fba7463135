"""Batched offline solve variants against frame by frame, in one process: CPU time and accuracy.

    PYTHONPATH=. python research/offline_steps.py VARIANT[,VARIANT...] [--files 3] [--skip 0]
        [--frames 300] [--preset 6]

A variant is ``fbf`` (the frame-by-frame offline solve: ``solve_clip`` switched off),
``batch`` (the batched solve as shipped) or ``batch`` followed by ``+NAME=VALUE`` items
that set module constants of :mod:`engine.methods.dragposer_batch` for that variant (a
Python expression each, e.g. ``batch+STEPS={}`` for the stopping rule,
``batch+STEPS={'adam-carry':40}+WARMUP_STEPS=10``), or one of the ablations of
:data:`ABLATIONS` (``batch+cut``: no cross-fade at segment starts; ``batch+mean_start``:
later segments start from the mean latent instead of the pose bank's). Per variant it prints each file's
Pos and Rot, then the CPU milliseconds per frame (``time.thread_time`` around
``evaluate_clip``, one torch and one BLAS thread) and the means of the metrics over the
files; with ``--parts``, also each part's share of the variant's CPU time (the decoder
passes, FK and losses, the after-solve steps, the bank lookups, reading the frames: each
wrapped in a CPU timer) and the decoder columns per frame. Files: the validation split of ``assets/models/README.md`` (Data), from
``../shared/data/mocap``.
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import numpy as np
import torch
from threadpoolctl import threadpool_limits

DATA = Path(__file__).resolve().parents[2] / "shared" / "data" / "mocap"
VAL = [
    "cmu_daz/indian/14.bvh",
    "cmu_daz/salsa/07.bvh",
    "cmu_iclone/002_01.bvh",
    "cmu_iclone/002_09.bvh",
    "cmu_iclone/005_05.bvh",
    "cmu_iclone/005_13.bvh",
    "cmu_iclone/006_02.bvh",
    "cmu_iclone/006_10.bvh",
    "cmu_iclone/007_05.bvh",
]
#: Ablations of the shipped batched solve: the name of a ``+NAME`` item, the function of
#: :mod:`engine.methods.dragposer_batch` it replaces, and its stand-in.
ABLATIONS = {
    "cut": ("_crossfade", lambda own, warm, offsets: None),
    "mean_start": ("_starts", lambda read, first, latent_dim: np.zeros((len(first), latent_dim), np.float32)),
}
KEYS = ("pos_cm", "rot_deg", "ee_cm", "jitter", "vel_cms", "iterations_mean")


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("variants", help="comma-separated: fbf, batch, batch+NAME=VALUE...")
    ap.add_argument("--files", type=int, default=3)
    ap.add_argument("--skip", type=int, default=0, help="start at this validation file")
    ap.add_argument("--frames", type=int, default=300)
    ap.add_argument("--preset", default="6")
    ap.add_argument("--parts", action="store_true", help="CPU share of each part of the solve")
    a = ap.parse_args()
    torch.set_num_threads(1)
    import engine.methods.dragposer_batch as DB
    from engine.cli.evaluate import evaluate_clip
    from engine.methods import get_method
    from engine.motion.retarget import load_motion

    shipped = {k: getattr(DB, k) for k in dir(DB) if k.isupper()}
    shipped.update({f: getattr(DB, f) for f, _ in ABLATIONS.values()})

    def method(variant: str):
        for k, v in shipped.items():
            setattr(DB, k, v)
        m = get_method("dragposer", mode="offline")
        if variant == "fbf":
            m.solve_clip = lambda frames: None  # the caller steps frame by frame
        for item in variant.split("+")[1:]:
            if item in ABLATIONS:
                setattr(DB, *ABLATIONS[item])
                continue
            name, value = item.split("=", 1)
            if name not in shipped or not name.isupper():
                raise SystemExit(f"{name}: not a constant of engine.methods.dragposer_batch")
            setattr(DB, name, eval(value))  # noqa: S307 - the user's own expression
        return m

    parts = _timed_parts(DB) if a.parts else None
    motions = [load_motion(DATA / f).slice(0, a.frames) for f in VAL[a.skip : a.skip + a.files]]
    with threadpool_limits(limits=1):
        for variant in a.variants.split(","):
            m = method(variant)
            evaluate_clip(motions[0].slice(0, 8), m, a.preset, progress=False)  # warm-up
            rows, cpu = [], 0.0
            if parts is not None:
                parts.clear()
            for mo in motions:
                c0 = time.thread_time()
                rows.append(evaluate_clip(mo, m, a.preset, progress=False))
                cpu += time.thread_time() - c0
                print(f"    {mo.name[:14]:<14} pos {rows[-1]['pos_cm']:.3f}  rot {rows[-1]['rot_deg']:.3f}", flush=True)
            n = sum(len(mo) for mo in motions)
            mean = {k: float(np.mean([r[k] for r in rows])) for k in KEYS}
            print(
                f"{variant} preset {a.preset}: cpu {1000 * cpu / n:.2f} ms/frame  "
                + "  ".join(f"{k} {mean[k]:.3f}" for k in KEYS),
                flush=True,
            )
            if parts is not None:
                print(f"    decoder columns per frame {parts.pop('columns', 0.0) / n:.1f}")
                for k in sorted(parts, key=lambda k: -parts[k]):
                    print(f"    {k:<22} {100 * parts[k] / cpu:5.1f} %")
    return 0


def _timed_parts(db) -> dict[str, float]:
    """Wrap the parts of the batched solve in CPU timers; returns the dict they add to
    (seconds per part, and ``columns``: decoder columns)."""
    import engine.solver.tracker_prior as TP
    from engine.models.fused import DenseDecoder
    from engine.solver.objective import FastObjective

    spent: dict[str, float] = {}

    def wrap(owner, name: str, label: str, columns: bool = False) -> None:
        orig = getattr(owner, name)

        def timed(*args, **kw):
            t = time.thread_time()
            out = orig(*args, **kw)
            spent[label] = spent.get(label, 0.0) + time.thread_time() - t
            if columns:
                z = args[1]
                spent["columns"] = spent.get("columns", 0.0) + (z.shape[1] if z.ndim == 2 else 1)
            return out

        setattr(owner, name, timed)

    wrap(DenseDecoder, "forward", "decoder forward", columns=True)
    wrap(DenseDecoder, "backward", "decoder reverse")
    wrap(FastObjective, "evaluate_rows", "FK and losses")
    wrap(FastObjective, "pose_gradient", "FK and losses reverse")
    wrap(db, "_finished", "after-solve steps")
    wrap(TP.PoseBank, "latent_frames", "bank lookups")
    wrap(db, "_plan", "reading frames")
    return spent


if __name__ == "__main__":
    raise SystemExit(main())
