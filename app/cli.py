"""``dragposer-studio gui``: open the desktop studio.

Registered from the app side: ``pyproject.toml`` names this module in the
``dragposer_studio.subcommands`` entry-point group, which :mod:`engine.cli.main` reads,
so the engine's command line never imports the app. Qt is imported only when it runs.
"""

from __future__ import annotations

import argparse
import gc
import sys
from pathlib import Path
from typing import Any

from engine.cli.rig_options import add_rig_map_option, rig_map_path
from engine.errors import UserError
from engine.studio.events import PLAYBACK_PACES

SHIPPED_VAE = Path(__file__).resolve().parents[1] / "assets" / "models" / "vae.pt"


def default_method() -> str:
    """DragPoser with the shipped model; the IK baseline when no weights are installed."""
    return "dragposer" if SHIPPED_VAE.is_file() else "ik"


def register(subparsers: argparse._SubParsersAction) -> None:
    p = subparsers.add_parser(
        "gui",
        help="open the studio window",
        description="Open the studio on FILE (or the bundled example clip). With --screenshot, "
        "play --after-frames frames, save a PNG of the whole window and exit.",
    )
    p.add_argument("file", nargs="?", metavar="FILE.bvh", help="motion to open")
    add_rig_map_option(p)
    p.add_argument(
        "--method",
        help="reconstruction method (default: dragposer with the shipped model, ik when no weights are installed)",
    )
    p.add_argument("--sensors", metavar="PRESET", help="sensor preset name")
    p.add_argument("--ghosts", metavar="A,B", help="other methods drawn as ghosts beside it, e.g. ik,sparseposer")
    p.add_argument(
        "--scene",
        metavar="SCENE.json",
        help="apply a saved scene (sensors, constraints, settings, "
        "method, frame) to FILE; without FILE the scene's own clip opens",
    )
    p.add_argument("--screenshot", metavar="OUT.png", help="save a screenshot and exit")
    p.add_argument("--after-frames", type=int, default=60, metavar="N", help="frames to play first (60)")
    p.add_argument(
        "--pace",
        choices=PLAYBACK_PACES,
        help="playback: solve every frame (default) or keep real time, skipping frames",
    )
    # "mode" is the optimizer's realtime/offline elsewhere; the old spelling still works
    p.add_argument("--mode", dest="old_pace", choices=PLAYBACK_PACES, help=argparse.SUPPRESS)
    p.add_argument(
        "--measure",
        type=float,
        metavar="SECONDS",
        help="play SECONDS, write smoothness figures (draws/s, solved/s, event-loop "
        "lateness, per-panel cost) to --json and exit",
    )
    p.add_argument("--json", metavar="OUT.json", default="measure.json", help="where --measure writes")
    p.add_argument(
        "--view",
        choices=("stick", "body"),
        default="stick",
        help="draw the reconstruction as a stick figure (default) or a shaded body",
    )
    p.add_argument(
        "--engine",
        choices=("process", "thread"),
        default="process",
        help="run the solver in its own process (default: the window and the solver never "
        "wait for each other) or in a thread of the window's process",
    )
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    from engine.startup_trace import mark

    mark("gui start")
    if args.measure is not None and not args.measure > 0:
        raise UserError(f"--measure: SECONDS must be > 0, got {args.measure}")
    if args.old_pace is not None:
        print("gui: --mode is deprecated, use --pace", file=sys.stderr)
    ghosts = tuple(g.strip() for g in (args.ghosts or "").split(",") if g.strip())
    if args.after_frames < 1:
        raise UserError(f"--after-frames: N must be >= 1, got {args.after_frames}")
    method = args.method or default_method()
    started = _start_engine(method) if args.engine == "process" else None
    # no cyclic collections while the start-up imports create their ~4 * 10^5 long-lived
    # objects (a fifth of the imports' time went to collections that freed nothing); the
    # window freezes them, and from then on cycles are collected between events
    # (app.collector, started by app.main.run)
    gc.disable()
    try:
        from app.main import run as run_app  # Qt loads only when the window opens

        mark("Qt, VTK and the window's modules imported")
        return run_app(
            args.file,
            method,
            args.sensors,
            args.screenshot,
            args.after_frames,
            args.measure,
            args.json,
            args.pace or args.old_pace,
            ghosts,
            args.view,
            rig_map_path(args),
            args.engine,
            args.scene,
            args.method is not None,
            started,
        )
    finally:
        gc.enable()
        if started is not None:
            started.stop()  # already stopped when the window closed; at once when it never opened


def _start_engine(method: str) -> Any:
    """The solver's process, started before this process imports Qt, VTK and the
    window's modules, building ``method`` at once: its imports (torch) and the models'
    loading then run on the other core in the same seconds, instead of after the window
    is built (a scene that names another method builds that one too, when it is read)."""
    from engine.studio.process import EngineProcess

    engine = EngineProcess(prepare=method)
    engine.start()
    return engine
