"""A/B of DragPoser's per-frame cost outside the optimizer iterations: a git revision
against the working tree, at 1 and at N iterations per frame, interleaved frame by frame
in one process (for a busy machine: compare the two, don't read absolute figures).

    PYTHONPATH=. python research/frame_cost_ab.py --baseline REV [--frames 200] [--iterations 10] [--sensors 6]

Per version and iteration count: the thread's CPU time of ``step`` per frame (median,
mean, p95, max, min; the first 10 frames left out) and, where the version has it, of
``between_frames`` (the predictor pieces a live loop runs after the pose is out; not
part of ``step``). The cost outside the iterations is about the 1-iteration figure
minus one iteration ((N-iteration - 1-iteration) / (N - 1)).
"""

from __future__ import annotations

import argparse
import tempfile
import time
from pathlib import Path

import numpy as np
import torch

from ab_versions import ROOT, EngineVersion, checkout

CLIP = ROOT / "assets" / "clips" / "example.bvh"


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--baseline", required=True, help="git revision to compare with")
    ap.add_argument("--frames", type=int, default=200)
    ap.add_argument("--iterations", type=int, default=10)
    ap.add_argument("--sensors", default="6")
    a = ap.parse_args()
    torch.set_num_threads(1)
    with tempfile.TemporaryDirectory() as tmp:
        runs = []
        for v in (EngineVersion(checkout(a.baseline, Path(tmp)), f"{a.baseline}"), EngineVersion(ROOT, "working tree")):
            for it in (1, a.iterations):
                with v:
                    from engine.methods.dragposer import DragPoserMethod
                    from engine.models import load_default_models
                    from engine.motion.retarget import load_motion
                    from engine.tracking import simulate

                    motion = load_motion(CLIP)
                    models = load_default_models()
                    m = DragPoserMethod(models.vae, models.predictor, iterations=it)
                    m.reset(motion.skeleton, motion.fps)
                    runs.append((v, it, m, simulate(motion, a.sensors), [], []))
        n = min(a.frames, len(runs[0][3]))
        for i in range(n):
            for v, _, m, tracking, steps, between in runs if i % 2 else runs[::-1]:
                with v:
                    c0 = time.thread_time()
                    m.step(tracking.frame(i))
                    steps.append(time.thread_time() - c0)
                    if hasattr(m, "between_frames"):
                        c0 = time.thread_time()
                        m.between_frames()
                        between.append(time.thread_time() - c0)
        for v, it, _, _, steps, between in runs:
            t = 1000.0 * np.array(steps[10:])
            line = (
                f"{v.label:<14} {it:3d} it  step cpu ms median {np.median(t):6.2f} mean {t.mean():6.2f} "
                f"p95 {np.percentile(t, 95):6.2f} max {t.max():6.2f} min {t.min():6.2f}"
            )
            if between:
                b = 1000.0 * np.array(between[10:])
                line += f" | between_frames mean {b.mean():5.2f} max {b.max():5.2f}"
            print(line, flush=True)


if __name__ == "__main__":
    main()
