"""The fast path's pieces, old code against new, interleaved in one process.

    PYTHONPATH=. python research/solver_pieces_ab.py [--baseline 5a69a12] [--repeats 2000]

For each version (:mod:`ab_versions`), one frame of the bundled clip is set up exactly as
the solver does (6 sensors, realtime), then each piece of an iteration is timed alone,
the versions alternating call by call: decoder forward, FK + losses, FK + losses
reverse, decoder backward. Prints the minimum and median (microseconds, thread CPU
time) per piece: on a busy machine the minimum is the figure to compare.
"""

from __future__ import annotations

import argparse
import tempfile
import time
from pathlib import Path

import numpy as np
import torch
from threadpoolctl import threadpool_limits

from ab_versions import ROOT, EngineVersion, checkout

CLIP = ROOT / "assets" / "clips" / "example.bvh"


def _setup(v: EngineVersion):
    """A FastPose of version ``v`` set up on frame 20 of the clip, and a latent."""
    with v:
        from engine.methods.dragposer import DragPoserMethod
        from engine.models import load_default_models
        from engine.motion.retarget import load_motion
        from engine.tracking import simulate

        motion = load_motion(CLIP)
        tracking = simulate(motion, "6")
        models = load_default_models()
        m = DragPoserMethod(models.vae, models.predictor, iterations=10)
        m.reset(motion.skeleton, motion.fps)
        for i in range(20):
            m.step(tracking.frame(i))
        return m.optimizer._fast, m._latent.detach().numpy().astype(np.float32)  # set up for frame 20


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--baseline", default="5a69a12")
    ap.add_argument("--repeats", type=int, default=2000)
    a = ap.parse_args()
    torch.set_num_threads(1)
    with tempfile.TemporaryDirectory() as tmp, threadpool_limits(limits=1):
        versions = [EngineVersion(checkout(a.baseline, Path(tmp)), f"old {a.baseline}"), EngineVersion(ROOT, "new")]
        set_up = [_setup(v) for v in versions]
        pieces = {
            "decoder forward": lambda fp, z: fp.decoder.forward(z),
            "fk + losses": lambda fp, z: fp.after_decoder(z, fp._out_cache),
            "fk + losses reverse": lambda fp, z: fp.backward(),
            "decoder backward": lambda fp, z: fp.decoder.backward(fp._g_cache),
        }
        for fp, z in set_up:
            fp._out_cache = fp.decoder.forward(z)
            fp.after_decoder(z, fp._out_cache)
            fp._g_cache = np.array(fp.backward(), dtype=np.float32)
        times = {(p, k): [] for p in pieces for k in range(2)}
        for r in range(a.repeats):
            for p, f in pieces.items():
                for k in (0, 1) if r % 2 else (1, 0):
                    fp, z = set_up[k]
                    c0 = time.thread_time()
                    f(fp, z)
                    times[p, k].append(time.thread_time() - c0)
        print(f"{'piece':<22}" + "".join(f"{v.label:>28}" for v in versions))
        for p in pieces:
            cells = [f"min {1e6 * np.min(times[p, k]):7.1f} med {1e6 * np.median(times[p, k]):7.1f}" for k in range(2)]
            print(f"{p:<22}" + "".join(f"{c:>28}" for c in cells))
        tot = [sum(np.min(times[p, k]) for p in pieces) for k in range(2)]
        print(f"{'sum of minimums':<22}" + "".join(f"{1e6 * t:>28.1f}" for t in tot))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
