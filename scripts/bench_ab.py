"""A/B timing of the solver's fast and reference paths, interleaved frame by frame in one
process (for a busy machine: compare the two, don't read absolute figures).

    PYTHONPATH=. python scripts/bench_ab.py [--frames 200] [--sensors 6] [--iterations 10]
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import numpy as np
import torch

from engine.methods.dragposer import DragPoserMethod
from engine.models import load_default_models
from engine.retarget import load_motion
from engine.tracking import simulate


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--frames", type=int, default=200)
    ap.add_argument("--sensors", default="6")
    ap.add_argument("--iterations", type=int, default=10)
    a = ap.parse_args()
    torch.set_num_threads(1)
    models = load_default_models()
    motion = load_motion(Path(__file__).resolve().parents[1] / "assets" / "clips" / "example.bvh")
    tracking = simulate(motion, a.sensors)
    runs = {}
    for fast in (True, False):
        m = DragPoserMethod(models.vae, models.predictor, fast=fast, iterations=a.iterations)
        m.reset(motion.skeleton, motion.fps)
        runs[fast] = (m, [], [])
    n = min(a.frames, len(tracking))
    for i in range(n):
        for fast in ((True, False) if i % 2 else (False, True)):
            m, frame_ms, iter_ms = runs[fast]
            t0 = time.perf_counter()
            res = m.step(tracking.frame(i))
            if i >= 10:
                frame_ms.append(1000.0 * (time.perf_counter() - t0))
                iter_ms.append(res.timings)
    for fast in (True, False):
        _, frame_ms, iter_ms = runs[fast]
        f = np.array(frame_ms)
        it = np.array([t["ms_per_iteration"] for t in iter_ms])
        parts = {k: np.median([t[k] for t in iter_ms]) for k in ("decoder", "fk_losses", "backward", "step")}
        print(f"{'fast' if fast else 'reference':<9} frame ms median {np.median(f):7.2f} min {f.min():7.2f} | "
              f"ms/iteration median {np.median(it):6.3f} min {it.min():6.3f} | "
              + " ".join(f"{k} {v:.3f}" for k, v in parts.items()))


if __name__ == "__main__":
    main()
