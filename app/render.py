"""``dragposer-studio render IN.bvh|SCENE.json --out OUT.mp4``: a motion as a video, headless.

Registered from the app side through the ``dragposer_studio.subcommands`` entry point
(like ``gui``), so the engine never imports PyVista. The frames are drawn off-screen by
VTK (EGL without a display, or the X server under Xvfb) with the studio's own drawables
(:mod:`app.render_scene`) and encoded to H.264 MP4 by the ffmpeg binary that the
``imageio-ffmpeg`` wheel ships (no system ffmpeg), running beside the drawing
(:mod:`app.video_encoder`), into a temporary file moved over ``OUT.mp4`` when complete.
The video has exactly the motion's frame count at ``--fps`` (the motion resampled when
it differs) and exactly ``--size``.

A scene is baked first (:mod:`engine.authoring.bake`, as ``bake`` does). ``--sensors P``
draws the trackers of preset P on the motion; ``--ghosts ik,...`` reconstructs the
motion from those trackers with each method, solved ahead in a process of its own
(:mod:`engine.studio.ghost_solve`), and draws the results over it (``--layout overlay``)
or beside it (``--layout side``). The legend names every figure in its colour.

``--start F --end F`` render a part of the clip: frames counted from 0 as the studio's
timeline shows them (the studio opens a clip at 60 fps; at another video rate, a
120 fps file rendered at its own rate or ``--fps``, the part is the same stretch of
time). The part is cut before anything is solved: a ghost starts solving at its first
frame, as on a clip that begins there (a method that follows the motion over time,
such as dragposer, starts afresh; the poses can differ from those of the whole clip at
the same frame). The time code still shows the clip's time and frame numbers.
"""

from __future__ import annotations

import argparse
import dataclasses
import math
import os
import sys
import time
from collections.abc import Callable
from pathlib import Path

from app.render_scene import CAMERAS, LAYOUTS, VIEWS, RenderOptions
from engine import skeleton as sk
from engine.errors import UserError


def register(subparsers: argparse._SubParsersAction) -> None:
    p = subparsers.add_parser(
        "render",
        help="render a motion or an authored scene to an MP4 video, off-screen",
        description="Draw IN.bvh (or the baked motion of SCENE.json) off-screen and encode it as H.264 MP4.",
    )
    p.add_argument("input", type=Path, metavar="IN.bvh|SCENE.json", help="motion or authoring scene")
    p.add_argument("--out", type=Path, required=True, metavar="OUT.mp4", help="video to write")
    p.add_argument("--size", default="960x540", metavar="WxH", help="frame size in pixels, even numbers (960x540)")
    p.add_argument("--fps", type=float, metavar="F", help="frame rate (default: the motion's)")
    p.add_argument("--sensors", metavar="P", help="draw the trackers of sensor preset P")
    p.add_argument("--ghosts", metavar="A,B", help="methods reconstructing from --sensors, drawn with the motion")
    p.add_argument("--view", choices=VIEWS, default="sticks", help="stick figure (default) or shaded body")
    p.add_argument(
        "--layout",
        choices=LAYOUTS,
        default="overlay",
        help="ghosts as thin sticks over the motion (default) or each figure in a panel of its own",
    )
    p.add_argument(
        "--camera",
        choices=CAMERAS,
        default="follow",
        help="fixed from the front or the side, or following the root (default)",
    )
    p.add_argument(
        "--truth",
        action="store_true",
        help="the input is the ground truth: drawn green and named 'ground truth' in the legend",
    )
    p.add_argument("--title", default="", metavar="TEXT", help="a title line above the legend")
    p.add_argument("--timecode", action="store_true", help="show the time and frame number (bottom right)")
    p.add_argument(
        "--start",
        type=int,
        metavar="F",
        help="first frame to render, counted from 0 as the studio's timeline counts (default 0); "
        "ghosts start solving there",
    )
    p.add_argument(
        "--end",
        type=int,
        metavar="F",
        help="last frame to render, included, as the timeline counts (default: the last)",
    )
    p.add_argument(
        "--msaa",
        type=int,
        default=0,
        metavar="N",
        help="multisampling anti-aliasing samples (default 0: fastest on software GL)",
    )
    p.add_argument("--no-progress", action="store_true", help="hide the progress bar")
    p.set_defaults(func=run)


def parse_size(text: str) -> tuple[int, int]:
    """``"WxH"`` -> (W, H); both even (H.264 4:2:0) and within 16-7680."""
    try:
        w, h = (int(v) for v in text.lower().split("x"))
    except ValueError:
        raise UserError(f"--size: expected WxH such as 960x540, got {text!r}") from None
    if not (16 <= w <= 7680 and 16 <= h <= 7680) or w % 2 or h % 2:
        raise UserError(f"--size {text}: width and height must be even numbers within 16-7680")
    return w, h


def options_from_args(args: argparse.Namespace) -> RenderOptions:
    """The video options of ``render``'s arguments, checked (:class:`engine.errors.UserError`)."""
    ghosts = tuple(g.strip() for g in (args.ghosts or "").split(",") if g.strip())
    if args.msaa not in (0, 2, 4, 8):
        raise UserError(f"--msaa must be 0, 2, 4 or 8, got {args.msaa}")
    options = RenderOptions(
        size=parse_size(args.size),
        sensors=args.sensors,
        ghosts=ghosts,
        view=args.view,
        camera=args.camera,
        layout=args.layout,
        truth=args.truth,
        title=args.title,
        timecode=args.timecode,
        msaa=args.msaa,
    )
    check_options(options)
    return options


def check_options(options: RenderOptions) -> None:
    """Refuse a video that cannot be made, before any file is chosen or frame drawn:
    ghosts without trackers, an unknown method or tracker preset, or a ghost method that
    cannot run from these trackers (:func:`engine.methods.presets.preset_problem`)."""
    from engine.methods import available_methods
    from engine.methods.presets import preset_problem

    if options.sensors:
        from app.render_scene import preset_sensors

        preset_sensors(options.sensors)  # a known preset
    if not options.ghosts:
        return
    if not options.sensors:
        raise UserError("--ghosts needs --sensors (the trackers they reconstruct from)")
    unknown = [g for g in options.ghosts if g not in available_methods()]
    if unknown:
        raise UserError(f"--ghosts: unknown method {unknown[0]!r}; known: {', '.join(available_methods())}")
    for ghost in options.ghosts:
        problem = preset_problem(ghost, options.sensors)
        if problem:
            raise UserError(f"--ghosts {ghost}: {problem}")


def run(args: argparse.Namespace) -> int:
    from tqdm import tqdm

    from engine.validation import check_input_file, check_output_path

    options = options_from_args(args)
    check_input_file(args.input, "scene" if args.input.suffix.lower() == ".json" else "BVH file")
    check_output_path(args.out)
    if args.fps and not 1.0 <= args.fps <= 240.0:
        raise UserError(f"--fps must be within 1-240, got {args.fps}")
    for flag, value in (("--start", args.start), ("--end", args.end)):
        if value is not None and value < 0:
            raise UserError(f"{flag} {value}: frames are counted from 0")
    if args.start is not None and args.end is not None and args.end < args.start:
        raise UserError(f"--end {args.end} is before --start {args.start}")
    motion = load_input(args.input)
    # the frames the studio's timeline numbers: a clip's at 60 fps (as the studio opens
    # it), a scene's at its bake's rate
    timeline_fps = motion.fps if args.input.suffix.lower() == ".json" else float(sk.FPS)
    if args.fps:
        from engine.motion.retarget import resample_motion

        motion = resample_motion(motion, float(args.fps))
    frames = timeline_range(args.start, args.end, motion, timeline_fps)
    options = dataclasses.replace(options, frames=frames)
    total = len(motion) if frames is None else frames[1] - frames[0] + 1
    bar = tqdm(
        total=total,
        unit="frame",
        desc="render",
        disable=args.no_progress,
        file=sys.stderr,
        bar_format="{l_bar}{bar}| {n_fmt}/{total_fmt} [{elapsed}<{remaining} left, {rate_fmt}]",
    )
    try:
        render_video(motion, args.out, options, lambda f: bar.update(1))
    finally:
        bar.close()
    w, h = options.size
    part = f" (frames {frames[0]}-{frames[1]} of {len(motion)})" if frames is not None else ""
    print(f"{args.out}: {total} frames{part}, {w}x{h} at {motion.fps:g} fps")
    return 0


def timeline_range(start: int | None, end: int | None, motion, timeline_fps: float) -> tuple[int, int] | None:
    """The frames of ``motion`` (first, last, inclusive) showing the timeline's frames
    ``start``-``end`` (None: the first, the last), where the timeline counts frames from
    0 at ``timeline_fps``; None for the whole motion. At the timeline's rate the
    numbers are the same; at another the part is the same stretch of time.

    Raises
    ------
    UserError
        A frame outside the clip (the message names the option and the frames there
        are) or ``--end`` before ``--start``.
    """
    if start is None and end is None:
        return None
    fps, n = float(motion.fps), len(motion)
    same = abs(fps - timeline_fps) < 1e-6
    last = n - 1 if same or n < 2 else int(math.floor((n - 1) / fps * timeline_fps + 1e-9))
    first_tl = 0 if start is None else start
    last_tl = last if end is None else end
    for flag, value in (("--start", first_tl), ("--end", last_tl)):
        if not 0 <= value <= last:
            raise UserError(f"{flag} {value}: the clip's frames are 0-{last} (as the studio's timeline counts them)")
    if last_tl < first_tl:
        raise UserError(f"--end {last_tl} is before --start {first_tl}")
    if same:
        return first_tl, last_tl
    nearest = lambda frame: min(n - 1, math.floor(frame * fps / timeline_fps + 0.5))  # noqa: E731
    return nearest(first_tl), max(nearest(first_tl), nearest(last_tl))


def check_frames(frames: tuple[int, int] | None, n: int) -> tuple[int, int]:
    """``frames`` (first, last, inclusive) of an ``n``-frame motion, checked; None: all.

    Raises
    ------
    UserError
        A frame outside 0..n-1, or the last before the first.
    """
    if frames is None:
        return 0, n - 1
    first, last = frames
    if not 0 <= first <= last <= n - 1:
        raise UserError(f"frames {first}-{last}: the motion's frames are 0-{n - 1}")
    return first, last


def load_input(path: Path):
    """A BVH clip (retargeted to the canonical skeleton) or a scene's baked motion."""
    if path.suffix.lower() == ".json":
        from engine.authoring.bake import bake
        from engine.authoring.document import load_authoring
        from engine.models import load_default_models

        return bake(load_authoring(path), load_default_models().vae).motion
    from engine.studio.clips import load_clip

    return load_clip(path, own_rate=True)


def render_video(
    motion,
    out: Path,
    options: RenderOptions = RenderOptions(),
    progress: Callable[[int], None] | None = None,
    timings: dict[str, float] | None = None,
    cancelled: Callable[[], bool] | None = None,
) -> None:
    """Draw the frames ``options.frames`` of ``motion`` (every frame when None)
    off-screen and write ``out`` (H.264 MP4) atomically.

    The part is cut first: the ghosts solve it alone, from its first frame, and the
    time code shows the clip's frame numbers. The ghosts' solve (a process), the
    drawing (this thread and Mesa's) and the encoding (ffmpeg, fed by a thread) run at
    once; ``progress(i)`` is called as the part's frame ``i`` (from 0) is handed to the
    encoder. ``cancelled()``, asked after every frame and while waiting for the ghosts,
    stops the video when it answers True (:class:`engine.progress.Cancelled`, nothing
    written). ``timings``, when given, sums the seconds spent in each step of the loop
    (``research/bench_render.py`` prints them per frame)."""
    from app.render_scene import FrameRenderer
    from app.video_encoder import VideoEncoder
    from engine.atomic import atomic_path
    from engine.progress import check

    first, last = check_frames(options.frames, len(motion))
    clip_frames = len(motion)
    if (first, last) != (0, clip_frames - 1):
        motion = motion.slice(first, last + 1)

    # llvmpipe's rasteriser threads: one, since ffmpeg and the ghosts' solve have the
    # other core (set before the first GL context; the studio does the same)
    os.environ.setdefault("LP_NUM_THREADS", str(max(1, (os.cpu_count() or 2) - 1)))
    headless_gl()
    clock = _Stopwatch(timings)
    ghosts = _start_ghosts(motion, options)
    try:
        scene = FrameRenderer(motion, options, first, clip_frames)
        try:
            with atomic_path(out, suffix=".mp4") as tmp:
                encoder = VideoEncoder(tmp, options.size, motion.fps)
                clock.lap("setup")
                try:
                    for f in range(len(motion)):
                        posed = ghosts.positions(f, cancelled) if ghosts is not None else None
                        clock.lap("ghost wait")
                        scene.pose(f, posed)
                        clock.lap("pose")
                        scene.window.Render()
                        clock.lap("render")
                        buf = encoder.buffer()
                        clock.lap("encoder wait")
                        scene.read_into(buf)
                        clock.lap("read pixels")
                        encoder.submit(buf)
                        if progress:
                            progress(f)
                        check(cancelled)
                        clock.lap("progress")
                except BaseException:
                    encoder.abort()
                    raise
                encoder.close()
                clock.lap("encoder finish")
        finally:
            scene.close()
    finally:
        if ghosts is not None:
            ghosts.close()


def headless_gl() -> None:
    """Without a display, ask VTK for an EGL window at once (libEGL is one of the system
    libraries ``make`` installs): VTK would try an X window first and print a warning
    ("bad X server connection") before it falls back. Left to VTK when a display is set,
    when the choice is already made, or when no libEGL is found (its own fall-backs)."""
    import ctypes.util

    if os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY"):
        return
    if ctypes.util.find_library("EGL"):
        os.environ.setdefault("VTK_DEFAULT_OPENGL_WINDOW", "vtkEGLRenderWindow")


class _Stopwatch:
    """Adds the seconds since the previous lap to ``timings[name]`` (nothing when None)."""

    def __init__(self, timings: dict[str, float] | None) -> None:
        self.timings = timings
        self.last = time.perf_counter()

    def lap(self, name: str) -> None:
        if self.timings is not None:
            now = time.perf_counter()
            self.timings[name] = self.timings.get(name, 0.0) + now - self.last
            self.last = now


def _start_ghosts(motion, options: RenderOptions):
    """The ghosts' solve, started at once (its process loads while the scene is built)."""
    check_options(options)
    if not options.ghosts:
        return None
    from app.render_scene import preset_sensors
    from engine.studio.ghost_solve import GhostSolves

    return GhostSolves(motion, preset_sensors(options.sensors), options.ghosts)


def main(argv: list[str] | None = None) -> int:
    """Run ``render`` alone (tests, and before the entry point is installed)."""
    from engine.cli.main import _Parser
    from engine.validation import one_line

    parser = _Parser(prog="dragposer-studio")
    register(parser.add_subparsers(dest="command"))
    args = parser.parse_args(["render", *(argv or [])])
    try:
        return int(args.func(args) or 0)
    except UserError as exc:
        print(f"error: {one_line(str(exc))}", file=sys.stderr)
        return 2


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
