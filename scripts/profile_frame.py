"""Where a realtime DragPoser frame goes: cProfile of ``step`` on the bundled clip, each
function's cumulative time as a share of the step's (nested rows overlap). Shares, not
milliseconds, are what a busy machine still gives.

    PYTHONPATH=. python scripts/profile_frame.py [--frames 300] [--warmup 20] [--sensors 6] [--rows 45]
"""

from __future__ import annotations

import argparse
import cProfile
import pstats


def main() -> None:
    """Profile the frames and print ``share  calls  file:line:function`` rows, largest first."""
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
    args = ap.parse_args()
    motion = load_motion(DEFAULT_CLIP)
    tracking = simulate(motion, args.sensors)
    method = get_method("dragposer", mode="realtime", iterations=args.iterations)
    driver.reset(method, motion.skeleton, motion.fps, reference=motion)
    n = min(len(tracking), args.warmup + args.frames)
    for i in range(args.warmup):
        driver.step(method, tracking.frame(i))
    prof = cProfile.Profile()
    prof.enable()
    for i in range(args.warmup, n):
        driver.step(method, tracking.frame(i))
    prof.disable()
    rows = sorted(((ct, f"{f}:{line}:{name}", nc) for (f, line, name), (_, nc, _, ct, _) in
                   pstats.Stats(prof).stats.items()), reverse=True)  # fmt: skip
    step = next(ct for ct, name, _ in rows if "methods/dragposer.py" in name and name.endswith(":step"))
    for ct, name, calls in rows[: args.rows]:
        print(f"{100.0 * ct / step:6.1f} %  {calls:6d}  {name.split('/engine/')[-1]}")


if __name__ == "__main__":
    main()
