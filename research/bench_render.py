"""How fast ``render`` makes a video, against the clip's own duration.

Runs ``python -m app.render`` on a clip for each configuration (default: 960x540 and
1280x720, body view, six trackers, an IK ghost) and prints the command's wall time, its
ratio to the clip's duration (1.0 = renders exactly as fast as it plays) and the CPU
seconds it used with its children (ffmpeg, the ghosts' solve): on a machine busy with
other work the wall time grows, the CPU time much less. Give
several trees with ``--tree`` (e.g. an unpacked older commit) to compare versions: the
runs alternate between trees, so a machine loaded by other work weighs on each alike.
Options only this tree knows (``--layout``) are passed to every tree, so compare with
``--extra ''`` against a tree from before them.

``--profile`` instead renders in this process and prints where a frame's time goes
(milliseconds per frame in each step of :func:`app.render.render_video`).

Needs a display for VTK: ``xvfb-run -a python research/bench_render.py``.
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import time
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
SHARED_CLIP = REPO.parent / "shared" / "data" / "mocap" / "cmu_iclone" / "005_04.bvh"
CLIP = SHARED_CLIP if SHARED_CLIP.is_file() else REPO / "assets" / "clips" / "example.bvh"
SIZES = ("960x540", "1280x720")


def main(argv: list[str] | None = None) -> int:
    sys.path.insert(0, str(REPO))  # this tree's packages, not an installed copy's
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("clip", nargs="?", type=Path, default=CLIP, help=f"BVH clip (default: {CLIP.name})")
    ap.add_argument("--size", action="append", help="frame size; repeat (default: 960x540 and 1280x720)")
    ap.add_argument(
        "--args",
        default="--view body --sensors 6 --ghosts ik",
        help="render options of every run (default: %(default)s)",
    )
    ap.add_argument("--extra", default="--layout overlay", help="options only this tree's render knows")
    ap.add_argument("--tree", action="append", type=Path, help="source tree to time; repeat (default: this one)")
    ap.add_argument("--repeat", type=int, default=1, help="runs per tree and size (default 1)")
    ap.add_argument("--profile", action="store_true", help="where a frame's time goes, in this process")
    args = ap.parse_args(argv)
    from engine.studio.clips import load_clip

    clip = load_clip(args.clip)
    duration = len(clip) / clip.fps
    print(
        f"{args.clip.name}: {len(clip)} frames at {clip.fps:g} fps = {duration:.2f} s; "
        f"{os.cpu_count()} CPUs, load {os.getloadavg()[0]:.2f}"
    )
    sizes = args.size or list(SIZES)
    if args.profile:
        return profile(clip, sizes, args.args + " " + args.extra)
    trees = args.tree or [REPO]
    for rep in range(args.repeat):
        for size in sizes:
            for tree in trees:
                extra = args.extra if tree.resolve() == REPO else ""
                cmd = [
                    sys.executable,
                    "-m",
                    "app.render",
                    str(args.clip.resolve()),
                    "--out",
                    os.devnull + ".mp4",
                    "--size",
                    size,
                    *args.args.split(),
                    *extra.split(),
                    "--no-progress",
                ]
                out = Path(f"/tmp/bench_render_{os.getpid()}.mp4")
                cmd[cmd.index(os.devnull + ".mp4")] = str(out)
                env = dict(os.environ, PYTHONPATH=str(tree.resolve()))
                t, cpu = time.perf_counter(), _children_cpu()
                res = subprocess.run(cmd, cwd=tree, env=env, capture_output=True, text=True)
                wall, cpu = time.perf_counter() - t, _children_cpu() - cpu
                out.unlink(missing_ok=True)
                status = "ok" if res.returncode == 0 else f"FAILED: {res.stderr.strip()[-300:]}"
                print(
                    f"run {rep + 1} {size:>9} {tree.resolve()}: {wall:6.2f} s = {wall / duration:.2f} x the clip, "
                    f"CPU {cpu:6.2f} s (load {os.getloadavg()[0]:.2f}) {status}",
                    flush=True,
                )
    return 0


def profile(clip, sizes: list[str], options: str) -> int:
    from app.render import options_from_args, register, render_video

    parser = argparse.ArgumentParser()
    register(parser.add_subparsers())
    for size in sizes:
        args = parser.parse_args(["render", "x.bvh", "--out", "x.mp4", "--size", size, *options.split()])
        timings: dict[str, float] = {}
        out = Path(f"/tmp/bench_render_{os.getpid()}.mp4")
        t, cpu, others = time.perf_counter(), time.process_time(), _children_cpu()
        render_video(clip, out, options_from_args(args), timings=timings)
        wall, cpu, others = time.perf_counter() - t, time.process_time() - cpu, _children_cpu() - others
        out.unlink(missing_ok=True)
        n = len(clip)
        loop = sum(v for k, v in timings.items() if k not in ("setup", "encoder finish"))
        print(
            f"{size} {options}: {wall:.2f} s in all; setup {timings['setup']:.2f} s, "
            f"frames {1000 * loop / n:.1f} ms each, encoder finish {timings['encoder finish']:.2f} s; "
            f"CPU per frame: {1000 * cpu / n:.1f} ms this process (drawing, Mesa, the writer), "
            f"{1000 * others / n:.1f} ms its children (ffmpeg, the ghosts' solve)"
        )
        for key, value in timings.items():
            if key not in ("setup", "encoder finish"):
                print(f"    {key:>14}: {1000 * value / n:6.2f} ms per frame")
    return 0


def _children_cpu() -> float:
    """User + system CPU seconds of every finished child process (and theirs) so far."""
    import resource

    use = resource.getrusage(resource.RUSAGE_CHILDREN)
    return use.ru_utime + use.ru_stime


if __name__ == "__main__":
    sys.exit(main())
