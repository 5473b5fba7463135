"""CPU time of the parts of a realtime DragPoser frame, per frame and as a share of the
step: each part is wrapped with ``time.thread_time`` (CPU seconds of the solving thread,
which a busy machine disturbs less than the wall clock), on the bundled clip after a
warm-up.

    PYTHONPATH=. python scripts/frame_sections.py [--frames 300] [--warmup 20] [--sensors 6]

Run it in two trees one after the other (and again, interleaved) to compare them.
"""

from __future__ import annotations

import argparse
import collections
import functools
import time


def main() -> None:
    """Print ``part  ms/frame  share`` rows, largest first, then the step outside the solve."""
    import torch

    import engine.methods.dragposer as dp
    import engine.methods.dragposer_root as roots
    import engine.solver.optimizer as opt
    import engine.solver.tracker_prior as tp
    from engine.cli.bench import DEFAULT_CLIP
    from engine.methods import driver, get_method
    from engine.motion.retarget import load_motion
    from engine.tracking import simulate

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--frames", type=int, default=300)
    ap.add_argument("--warmup", type=int, default=20)
    ap.add_argument("--sensors", default="6")
    ap.add_argument("--iterations", type=int, default=10)
    ap.add_argument("--threads", type=int, default=1, help="torch threads (default 1: steadier on a busy machine)")
    args = ap.parse_args()
    torch.set_num_threads(args.threads)
    spent: dict[str, float] = collections.defaultdict(float)

    def wrap(owner, name: str, label: str) -> None:
        f = getattr(owner, name)

        @functools.wraps(f)
        def timed(*a, **k):
            t = time.thread_time()
            try:
                return f(*a, **k)
            finally:
                spent[label] += time.thread_time() - t

        setattr(owner, name, timed)

    wrap(dp.DragPoserMethod, "_step", "step")
    wrap(opt.PoseOptimizer, "solve", "solve (iterations and their set-up)")
    wrap(tp.PoseBank, "latent", "pose-bank lookup")
    wrap(tp.TrackerHistory, "arrays", "tracker history")
    wrap(dp, "finish", "after-solve steps (limb_ik.finish)")
    wrap(dp.DragPoserMethod, "_advance", "next frame's history (_advance)")
    wrap(dp.DragPoserMethod, "_read_frame", "reading the frame (_read_frame)")
    for name in ("root_override", "reference_root", "root_anchor", "initial_root", "held_root"):
        wrap(roots, name, "root rules")
    motion = load_motion(DEFAULT_CLIP)
    tracking = simulate(motion, args.sensors)
    method = get_method("dragposer", mode="realtime", iterations=args.iterations)
    driver.reset(method, motion.skeleton, motion.fps, reference=motion)
    n = min(len(tracking), args.warmup + args.frames)
    for i in range(args.warmup):
        driver.step(method, tracking.frame(i))
    spent.clear()
    for i in range(args.warmup, n):
        driver.step(method, tracking.frame(i))
    frames, step = n - args.warmup, spent.pop("step")
    print(f"step: {1000 * step / frames:.3f} ms CPU per frame over {frames} frames")
    for label, s in sorted(spent.items(), key=lambda kv: -kv[1]):
        print(f"  {label:40s} {1000 * s / frames:7.3f} ms  {100 * s / step:5.1f} %")
    out = step - spent["solve (iterations and their set-up)"]
    print(f"  {'outside the solve':40s} {1000 * out / frames:7.3f} ms  {100 * out / step:5.1f} %")


if __name__ == "__main__":
    main()
