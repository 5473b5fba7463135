"""Where a realtime DragPoser frame goes, on the bundled clip after a warm-up.

Default: cProfile of ``step``, each function's cumulative time as a share of the step's
(nested rows overlap). With ``--sections``: the CPU time (``time.thread_time``, which a
busy machine disturbs less than the wall clock) of each part of
``DragPoserMethod._step``, per frame and as a share, then what is outside the solve.
Shares and CPU times, not wall milliseconds, are what a busy machine still gives; run it
in two trees one after the other (and again, interleaved) to compare them.

    PYTHONPATH=. python research/profile_frame.py [--frames 300] [--warmup 20] [--sensors 6] [--rows 45]
    PYTHONPATH=. python research/profile_frame.py --sections [--threads 1]
"""

from __future__ import annotations

import argparse
import collections
import cProfile
import functools
import pstats
import time


def _sections(run) -> None:
    """Wrap the parts of the step with CPU timers, ``run()`` the frames, print the table."""
    import engine.methods.dragposer as dp
    import engine.methods.dragposer_parts as parts
    import engine.methods.dragposer_prior as prior
    import engine.methods.dragposer_root as roots
    import engine.solver.optimizer as opt
    import engine.solver.tracker_history as th
    import engine.solver.tracker_prior as tp

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
    wrap(tp.PoseBank, "lookup", "pose-bank lookup")
    wrap(th.TrackerHistory, "arrays", "tracker history")
    wrap(parts.FramePlan, "finished", "after-solve steps (FramePlan.finished)")
    wrap(prior.PriorSource, "latent", "prior latent (bank and networks)")
    wrap(dp.DragPoserMethod, "_advance", "next frame's history (_advance)")
    wrap(dp.DragPoserMethod, "plan", "reading the frame (plan)")
    for name in ("root_override", "reference_root", "root_anchor", "initial_root", "held_root"):
        wrap(roots, name, "root rules")
    frames = run()
    step = spent.pop("step")
    print(f"step: {1000 * step / frames:.3f} ms CPU per frame over {frames} frames")
    for label, s in sorted(spent.items(), key=lambda kv: -kv[1]):
        print(f"  {label:40s} {1000 * s / frames:7.3f} ms  {100 * s / step:5.1f} %")
    out = step - spent["solve (iterations and their set-up)"]
    print(f"  {'outside the solve':40s} {1000 * out / frames:7.3f} ms  {100 * out / step:5.1f} %")


def main() -> None:
    """Profile the frames and print ``share  calls  file:line:function`` rows, largest
    first (or, with ``--sections``, the CPU time of each part)."""
    import torch

    from engine.cli.bench import DEFAULT_CLIP
    from engine.methods import driver, get_method
    from engine.motion.retarget import load_motion
    from engine.tracking import simulate

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--frames", type=int, default=300)
    ap.add_argument("--warmup", type=int, default=20)
    ap.add_argument("--sensors", default="6")
    ap.add_argument("--iterations", type=int, default=10)
    ap.add_argument("--rows", type=int, default=45)
    ap.add_argument("--sections", action="store_true", help="CPU time per part of the step instead of cProfile")
    ap.add_argument("--threads", type=int, help="torch threads (e.g. 1: steadier on a busy machine)")
    args = ap.parse_args()
    if args.threads:
        torch.set_num_threads(args.threads)
    motion = load_motion(DEFAULT_CLIP)
    tracking = simulate(motion, args.sensors)
    method = get_method("dragposer", mode="realtime", iterations=args.iterations)
    driver.reset(method, motion.skeleton, motion.fps, reference=motion)
    n = min(len(tracking), args.warmup + args.frames)
    for i in range(args.warmup):
        driver.step(method, tracking.frame(i))

    def run() -> int:
        for i in range(args.warmup, n):
            driver.step(method, tracking.frame(i))
        return n - args.warmup

    if args.sections:
        _sections(run)
        return
    prof = cProfile.Profile()
    prof.enable()
    run()
    prof.disable()
    rows = sorted(
        ((ct, f"{f}:{line}:{name}", nc) for (f, line, name), (_, nc, _, ct, _) in pstats.Stats(prof).stats.items()),
        reverse=True,
    )
    step = next(ct for ct, name, _ in rows if "methods/dragposer.py" in name and name.endswith(":step"))
    for ct, name, calls in rows[: args.rows]:
        print(f"{100.0 * ct / step:6.1f} %  {calls:6d}  {name.split('/engine/')[-1]}")


if __name__ == "__main__":
    main()
