"""``dragposer-studio bench``: how fast each method reconstructs, frame by frame (and,
with ``--pose-tasks``, the pose-mode benchmark of :mod:`engine.cli.pose_bench`).

Speed targets are measured here and reported, never asserted by timing tests: the
numbers depend on the machine. The report names the machine (cores, torch threads).
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import time
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from engine.cli import pose_bench
from engine.cli.rig_options import add_rig_map_option, asf_path, rig_map_path
from engine.solver.settings import MODES

if TYPE_CHECKING:
    from engine.methods import Method

REPO = Path(__file__).resolve().parents[2]
DEFAULT_CLIP = REPO / "assets" / "clips" / "example.bvh"


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "bench",
        help="measure milliseconds per frame of reconstruction methods",
        description="Simulate trackers from a clip and time each method's per-frame step "
        "(after a warm-up). Prints mean / median / 95th percentile ms per frame and "
        "iterations per frame.",
    )
    p.add_argument("file", nargs="?", type=Path, default=DEFAULT_CLIP, help="BVH clip (default: bundled example)")
    p.add_argument(
        "--method",
        action="append",
        help="method to time; repeat for several (default: every method that works with --sensors)",
    )
    p.add_argument("--sensors", default="6", help="sensor preset or list (default: 6)")
    p.add_argument("--mode", choices=MODES, default="realtime", help="optimizer mode")
    p.add_argument("--iterations", type=int, help="optimizer iterations per frame (realtime mode)")
    p.add_argument("--frames", type=int, default=300, help="frames to time (default: 300)")
    p.add_argument("--warmup", type=int, default=10, help="untimed frames first (default: 10)")
    p.add_argument("--json", type=Path, metavar="OUT", help="also write the results as JSON")
    p.add_argument(
        "--scene",
        type=Path,
        metavar="SCENE.json",
        help="also solve the scene's constraints with the sensors (methods that take constraints; "
        "the scene's optimizer settings are not applied)",
    )
    add_rig_map_option(p)
    pose_bench.add_options(p)
    p.set_defaults(func=_bench)


PARTS = ("decoder", "fk_losses", "backward", "step")


def bench_method(name: str, motion, tracking, frames: int, warmup: int, constraints=(), **kwargs) -> dict:
    """Time ``frames`` steps of method ``name`` after ``warmup`` untimed ones, with the
    user ``constraints`` (a scene's) besides the sensors.

    Per frame: wall-clock milliseconds of ``step`` (everything the method does for the
    frame). Per iteration (iterative methods): the solver's own milliseconds per
    iteration on each frame (:attr:`FrameResult.timings`), and its parts.
    """
    from engine.errors import UserError
    from engine.methods import driver, get_method

    method = get_method(name, **kwargs)
    if constraints and not driver.set_constraints(method, constraints):
        raise UserError(f"method {name!r} takes no constraints (--scene)")
    driver.reset(method, motion.skeleton, motion.fps, reference=motion)
    n = min(len(tracking), warmup + frames)
    times, iters, per_iter = [], [], []
    parts: dict[str, list[float]] = {k: [] for k in PARTS}
    batched = _solve_clip(method, tracking, n) if kwargs.get("mode") == "offline" else None
    if batched is not None:  # a batched offline solve: each frame costs the clip's time per frame
        ms, results = batched
        times = [ms] * (n - warmup)
        iters = [r.iterations for r in results[warmup:]]
        per_iter = [ms * len(results) / max(1, sum(r.iterations for r in results))]
        n = 0
    for i in range(n):
        t0 = time.perf_counter()
        res = driver.step(method, tracking.frame(i))
        dt = 1000.0 * (time.perf_counter() - t0)
        if i >= warmup:
            times.append(dt)
            iters.append(res.iterations)
            if res.timings:
                per_iter.append(res.timings["ms_per_iteration"])
                for k in PARTS:
                    parts[k].append(res.timings[k])
    t = np.asarray(times)
    row = {
        "method": name,
        "frames": int(t.size),
        "ms_mean": float(t.mean()),
        "ms_median": float(np.median(t)),
        "ms_p95": float(np.percentile(t, 95)),
        "fps": float(1000.0 / t.mean()),
        "iterations_mean": float(np.mean(iters)),
        "ms_per_frame_median": float(np.median(t)),
        "frames_per_s": float(1000.0 / t.mean()),
        "ms_per_iteration_median": float(np.median(per_iter)) if per_iter else None,
        "ms_per_iteration_p95": float(np.percentile(per_iter, 95)) if per_iter else None,
        "breakdown_ms": {k: float(np.median(v)) for k, v in parts.items()} if parts["decoder"] else None,
        "peak_rss_mb": _peak_rss_mb(),
    }
    return row


def _solve_clip(method: Method, tracking, n: int) -> tuple[float, list] | None:
    """``(ms per frame, results)`` of the method's whole-clip solve of the first ``n``
    frames (engine/methods/dragposer_batch.py), or None for a method that steps frame by frame."""
    from engine.methods import SolvesClips, driver

    if not isinstance(method, SolvesClips):
        return None
    t0 = time.perf_counter()
    results = driver.solve_clip(method, [tracking.frame(i) for i in range(n)])
    return None if results is None else (1000.0 * (time.perf_counter() - t0) / n, results)


def _peak_rss_mb() -> float:
    """Peak resident memory of this process so far, MiB (models included)."""
    import resource
    import sys

    peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    return peak / (1024.0 * 1024.0) if sys.platform == "darwin" else peak / 1024.0


def _bench(args: argparse.Namespace) -> int:
    import torch

    from engine.atomic import write_text
    from engine.errors import UserError
    from engine.methods import available_methods
    from engine.motion.retarget import load_motion
    from engine.scene import load_scene
    from engine.tracking import simulate
    from engine.validation import check_args, check_output_path

    check_args(args)
    if args.pose_tasks:
        return pose_bench.run(args, DEFAULT_CLIP)
    if args.json:
        check_output_path(args.json, "--json")
    motion = load_motion(args.file, rig_map=rig_map_path(args), asf=asf_path(args))
    if args.warmup + 1 > len(motion):
        raise UserError(f"{args.file}: only {len(motion)} frames, fewer than the warm-up")
    tracking = simulate(motion, args.sensors)
    constraints = load_scene(args.scene)[0] if args.scene else []
    names = args.method or list(available_methods())
    kwargs = {"mode": args.mode}
    if args.iterations:
        kwargs["iterations"] = args.iterations
    machine = {
        "cpu_count": os.cpu_count(),
        "torch_threads": torch.get_num_threads(),
        "torch": torch.__version__,
        "cuda": torch.cuda.is_available(),
        "platform": platform.platform(),
    }
    rows, skipped = [], []
    for name in names:
        kw = kwargs if name not in ("ik",) else {}
        try:
            rows.append(bench_method(name, motion, tracking, args.frames, args.warmup, constraints, **kw))
        except UserError as exc:
            if args.method:  # named on the command line: its failure is the answer
                raise
            skipped.append(f"{name}: skipped: {exc}")  # e.g. needs another sensor preset
    scene = f", scene {args.scene.name} ({len(constraints)} constraints)" if args.scene else ""
    print(
        f"{args.file.name}: sensors {args.sensors}{scene}, mode {args.mode}, "
        f"{machine['cpu_count']} cores, torch {machine['torch_threads']} threads"
    )
    print(
        f"{'method':<12} {'frames':>6} {'ms mean':>8} {'median':>8} {'p95':>8} {'fps':>7} {'iters':>6} "
        f"{'ms/it':>7} {'it p95':>7}  breakdown ms/it (decoder fk+losses backward step)"
    )
    for r in rows:
        it = r["ms_per_iteration_median"]
        extra = (
            ""
            if it is None
            else (
                f"{it:>7.3f} {r['ms_per_iteration_p95']:>7.3f}  "
                + " ".join(f"{v:.3f}" for v in (r["breakdown_ms"] or {}).values())
            )
        )  # none for a batched solve
        print(
            f"{r['method']:<12} {r['frames']:>6d} {r['ms_mean']:>8.2f} {r['ms_median']:>8.2f} "
            f"{r['ms_p95']:>8.2f} {r['fps']:>7.1f} {r['iterations_mean']:>6.1f} {extra}"
        )
    for line in skipped:
        print(line)
    if args.json:
        out = {"file": str(args.file), "sensors": args.sensors, "mode": args.mode, "machine": machine, "methods": rows}
        if args.scene:
            out["scene"] = str(args.scene)
        write_text(args.json, json.dumps(out, indent=1))
    return 0
