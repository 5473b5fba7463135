"""``dragposer-studio render IN.bvh|SCENE.json --out OUT.mp4``: a motion as a video, headless.

Registered from the app side through the ``dragposer_studio.subcommands`` entry point
(like ``gui``), so the engine never imports PyVista. The frames are drawn off-screen by
VTK (EGL without a display, or the X server under Xvfb) with the studio's own drawables
(:mod:`widgets.viewport`) and encoded to H.264 MP4 by the ffmpeg binary that the
``imageio-ffmpeg`` wheel ships (no system ffmpeg), into a temporary file moved over
``OUT.mp4`` when complete. The video has exactly the motion's frame count at ``--fps``
(the motion resampled when it differs) and exactly ``--size``.

A scene is baked first (:mod:`engine.authoring.bake`, as ``bake`` does). ``--sensors P``
draws the trackers of preset P on the motion; ``--ghosts ik,...`` reconstructs the
motion from those trackers with each method and draws the results beside it.
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Callable
from pathlib import Path

import numpy as np

from engine.errors import UserError

VIEWS = ("sticks", "body")
CAMERAS = ("front", "side", "follow")
#: Height of the camera's focus above the floor, metres (about the chest).
FOCUS_HEIGHT = 1.0


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
    p.add_argument("--ghosts", metavar="A,B", help="methods reconstructing from --sensors, drawn as ghosts")
    p.add_argument("--view", choices=VIEWS, default="sticks", help="stick figure (default) or shaded body")
    p.add_argument("--camera", choices=CAMERAS, default="follow",
                   help="fixed from the front or the side, or following the root (default)")  # fmt: skip
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


def run(args: argparse.Namespace) -> int:
    from tqdm import tqdm

    from engine.validation import check_input_file, check_output_path

    size = parse_size(args.size)
    check_input_file(args.input, "scene" if args.input.suffix.lower() == ".json" else "BVH file")
    check_output_path(args.out)
    ghosts = tuple(g.strip() for g in (args.ghosts or "").split(",") if g.strip())
    if ghosts and not args.sensors:
        raise UserError("--ghosts needs --sensors (the trackers they reconstruct from)")
    motion = load_input(args.input)
    if args.fps:
        if not 1.0 <= args.fps <= 240.0:
            raise UserError(f"--fps must be within 1-240, got {args.fps}")
        from engine.motion.retarget import resample_motion

        motion = resample_motion(motion, float(args.fps))
    bar = tqdm(total=len(motion), unit="frame", desc="render", disable=args.no_progress, file=sys.stderr)
    try:
        render_video(motion, args.out, size, motion.fps, args.sensors, ghosts, args.view, args.camera,
                     lambda f: bar.update(1))  # fmt: skip
    finally:
        bar.close()
    print(f"{args.out}: {len(motion)} frames, {size[0]}x{size[1]} at {motion.fps:g} fps")
    return 0


def load_input(path: Path):
    """A BVH clip (retargeted to the canonical skeleton) or a scene's baked motion."""
    if path.suffix.lower() == ".json":
        from engine.authoring.bake import bake
        from engine.authoring.document import load_authoring
        from engine.models import load_default_models

        return bake(load_authoring(path), load_default_models().vae).motion
    from engine.studio.clips import load_clip

    return load_clip(path, own_rate=True)


def render_video(motion, out: Path, size: tuple[int, int], fps: float, sensors: str | None = None,
                 ghosts: tuple[str, ...] = (), view: str = "sticks", camera: str = "follow",
                 progress: Callable[[int], None] | None = None) -> None:  # fmt: skip
    """Draw every frame of ``motion`` off-screen and write ``out`` (H.264 MP4) atomically."""
    import imageio_ffmpeg

    from engine.atomic import atomic_path

    frames = FrameRenderer(motion, size, sensors, ghosts, view, camera)
    try:
        with atomic_path(out, suffix=".mp4") as tmp:
            writer = imageio_ffmpeg.write_frames(str(tmp), size, fps=fps, codec="libx264", pix_fmt_out="yuv420p",
                                                 macro_block_size=1, quality=7, ffmpeg_log_level="error")  # fmt: skip
            writer.send(None)  # start ffmpeg
            try:
                for f in range(len(motion)):
                    writer.send(np.ascontiguousarray(frames.draw(f)))
                    if progress:
                        progress(f)
            finally:
                writer.close()
    finally:
        frames.close()


class FrameRenderer:
    """An off-screen PyVista scene of a motion; :meth:`draw` gives frame ``f`` as RGB
    ``(H, W, 3)`` uint8."""

    def __init__(self, motion, size: tuple[int, int], sensors: str | None, ghosts: tuple[str, ...], view: str,
                 camera: str) -> None:  # fmt: skip
        import pyvista as pv

        from widgets import style
        from widgets.viewport.body import BodyActor
        from widgets.viewport.floor import FloorGrid
        from widgets.viewport.skeleton import SkeletonActor

        self.positions = motion.positions()
        self.camera = camera
        self.plotter = pv.Plotter(off_screen=True, window_size=list(size))
        self.plotter.set_background(style.BACKGROUND_BOTTOM, top=style.BACKGROUND_TOP)
        FloorGrid(self.plotter)
        make = BodyActor if view == "body" else SkeletonActor
        self.actors = [(make(self.plotter, style.RECONSTRUCTION, name="motion"), self.positions)]
        self.sensor_points = None
        if sensors:
            joints, ghost_positions = _sensors_and_ghosts(motion, sensors, ghosts)
            for i, (name, pos) in enumerate(ghost_positions):
                self.actors.append((make(self.plotter, style.ghost_color(name, i), opacity=0.55, name=f"ghost-{name}"), pos))
            self.sensor_joints = joints
            self.sensor_points = pv.PolyData(self.positions[0, joints])
            self.plotter.add_mesh(self.sensor_points, color=style.SENSOR, point_size=16, render_points_as_spheres=True,
                                  pickable=False, reset_camera=False)  # fmt: skip
        self._centre = np.array([*self.positions[:, 0, :2].mean(axis=0), FOCUS_HEIGHT])

    def draw(self, f: int) -> np.ndarray:
        from widgets.viewport.camera import place_camera

        for actor, pos in self.actors:
            actor.update(pos[f])
        if self.sensor_points is not None:
            self.sensor_points.points = self.positions[f, self.sensor_joints]
        if self.camera == "follow":
            place_camera(self.plotter.camera, "home", np.array([*self.positions[f, 0, :2], FOCUS_HEIGHT]))
        else:
            place_camera(self.plotter.camera, self.camera, self._centre)
        self.plotter.render()
        return self.plotter.screenshot(return_img=True)[..., :3]

    def close(self) -> None:
        self.plotter.close()


def _sensors_and_ghosts(motion, preset: str, ghosts: tuple[str, ...]):
    from engine import skeleton as sk
    from engine.studio.clips import sensor_presets
    from engine.studio.export import reconstruct_clip

    presets = sensor_presets()
    if preset not in presets:
        raise UserError(f"--sensors: unknown preset {preset!r}; known: {', '.join(sorted(presets))}")
    sensors = presets[preset]
    joints = [sk.JOINT_INDEX[s.joint] for s in sensors]
    out = [(name, reconstruct_clip(motion, sensors, (), {}, name).positions()) for name in ghosts]
    return joints, out


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
