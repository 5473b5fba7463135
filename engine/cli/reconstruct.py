"""``dragposer-studio reconstruct IN.bvh --out OUT.bvh``: DragPoser on simulated trackers
(several inputs: ``reconstruct A.bvh B.bvh ... --out-dir DIR [--jobs N]``, one worker
process per file, see :mod:`engine.cli.jobs`);
``reconstruct --trackers REC.jsonl --out OUT.bvh``: on recorded trackers
(:mod:`engine.cli.reconstruct_trackers`).

The clip is loaded onto the canonical skeleton, trackers are simulated from it
(:func:`engine.tracking.simulate`: preset or joint list, optional faulty sensors and
hand-tracking gaps), DragPoser reconstructs it frame by frame (progress bar on stderr)
and the result is written as BVH or glTF (by ``--out``'s extension, docs/export.md).
A scene file (``--scene``, see ``docs/optimizer.md``) adds constraints and settings;
options given on the command line win over the scene's settings.
"""

from __future__ import annotations

import argparse
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from engine.cli.export_options import add_export_options, check_export, export_contents, run_ghosts
from engine.cli.jobs import add_jobs_option, executor_of, jobs_of, map_files
from engine.cli.method_options import add_model_options, build_method
from engine.cli.rig_options import add_rig_map_option, asf_path, rig_map_path
from engine.cli.tracker_options import add_tracker_options
from engine.errors import UserError
from engine.solver.settings import MODES


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "reconstruct",
        help="reconstruct a clip from simulated sparse trackers with DragPoser and save it as BVH",
        description="Simulate trackers from IN.bvh, reconstruct the full body with DragPoser "
        "(latent-space pose optimisation) and write OUT.bvh.",
    )
    p.add_argument(
        "input",
        type=Path,
        nargs="*",
        metavar="IN.bvh",
        help="source motion(s) (any supported rig); several need --out-dir",
    )
    p.add_argument(
        "--trackers",
        type=Path,
        metavar="REC.jsonl",
        help="reconstruct a tracker recording (from `live --record`; docs/trackers.md) instead of IN.bvh",
    )
    p.add_argument(
        "--out",
        type=Path,
        metavar="OUT.bvh",
        help="where to write the reconstruction (one input): .bvh, .glb or .gltf (docs/export.md)",
    )
    p.add_argument(
        "--out-dir",
        type=Path,
        metavar="DIR",
        help="write each input's reconstruction to DIR/<input name>.bvh (several inputs; --out-format)",
    )
    p.add_argument(
        "--on-source-rig",
        action="store_true",
        help="write the result onto IN.bvh's own hierarchy (its joint names, offsets and "
        "channels; joints outside the 22 keep their rest rotation) instead of the canonical one",
    )
    p.add_argument(
        "--fps",
        type=float,
        metavar="F",
        help="frame rate of the file written with --on-source-rig (default: the source's)",
    )
    add_rig_map_option(p)
    p.add_argument("--sensors", default="6", help="sensor preset or list, e.g. 6, 4, root,lwrist:3 (default: 6)")
    p.add_argument(
        "--mode",
        choices=MODES,
        help="realtime: fixed iterations per frame; "
        "offline: iterate until the sensor tolerances are met (default: realtime)",
    )
    p.add_argument(
        "--iterations", type=int, metavar="N", help="iterations per frame (realtime) or the cap per frame (offline)"
    )
    p.add_argument("--lr", type=float, metavar="LR", help="Adam learning rate on the latent")
    p.add_argument(
        "--faulty",
        type=float,
        default=0.0,
        metavar="P",
        help="per-frame probability that one sensor fails for 100 frames (DragPoser: 0.01)",
    )
    p.add_argument("--gaps", action="store_true", help="simulate hand-tracking gaps (RPM)")
    add_model_options(p)
    p.add_argument("--max-frames", type=int, metavar="N", help="reconstruct only the first N frames")
    p.add_argument("--scene", type=Path, metavar="SCENE.json", help="constraints and optimizer settings to add")
    p.add_argument("--seed", type=int, default=0, help="seed of the tracker simulation (default: 0)")
    p.add_argument("--method", default="dragposer", help=argparse.SUPPRESS)
    p.add_argument("--no-progress", action="store_true", help="hide the progress bar")
    add_tracker_options(p)
    add_export_options(p, ghosts=True, tracker_nodes=True, out_dir=True)
    add_jobs_option(p)
    p.set_defaults(func=_reconstruct)


def _reconstruct(args: argparse.Namespace) -> int:
    from engine.tracking import parse_sensors
    from engine.validation import check_args, check_input_file, check_output_path

    check_args(args)  # every number in range, outputs writable: before any work
    if args.out is not None:
        check_output_path(args.out, "--out")
    if getattr(args, "json", None):
        check_output_path(args.json, "--json")
    if args.trackers is not None:
        if args.input:
            raise UserError("give IN.bvh or --trackers REC.jsonl, not both (the clip can be --reference)")
        if args.on_source_rig:
            raise UserError("--on-source-rig writes onto IN.bvh's rig; it does not apply to --trackers")
        if args.out is None or args.out_dir is not None:
            raise UserError("--trackers needs --out OUT.bvh (not --out-dir)")
        if args.ghosts or args.tracker_nodes:
            raise UserError(
                "--ghosts and --tracker-nodes apply to IN.bvh reconstructions, not to --trackers recordings"
            )
        check_export(args, [args.out])
        from engine.cli.reconstruct_trackers import reconstruct_trackers

        return reconstruct_trackers(args)
    if not args.input:
        raise UserError("give IN.bvh or --trackers REC.jsonl")
    if args.out is not None and args.out_dir is not None:
        raise UserError("give --out (one input) or --out-dir, not both")
    if args.out_dir is None and (args.out is None or len(args.input) > 1):
        raise UserError(
            "several inputs need --out-dir DIR" if len(args.input) > 1 else "give --out OUT.bvh or --out-dir DIR"
        )
    for opt in ("calibrate", "reference", "json"):
        if getattr(args, opt):
            raise UserError(f"--{opt} applies to --trackers recordings")
    if args.map:
        raise UserError("--map applies to --trackers recordings")
    if args.fps is not None and not args.on_source_rig:
        raise UserError("--fps applies to --on-source-rig (the canonical file is written at 60 fps)")
    parse_sensors(args.sensors)  # fail before loading anything
    for path in args.input:
        check_input_file(path)
    outs = [args.out] if args.out is not None else [args.out_dir / f"{p.stem}.{args.out_format}" for p in args.input]
    check_export(args, outs, hint="give --out a .glb or .gltf name" if args.out else "add --out-format glb or gltf")
    if len(set(outs)) != len(outs):
        raise UserError("two inputs share a file name; their outputs in --out-dir would collide")
    if args.out_dir is not None:
        for out in outs:
            check_output_path(out, "--out-dir")
        args.out_dir.mkdir(parents=True, exist_ok=True)
    jobs, executor = jobs_of(args), executor_of(args)
    parallel = (jobs > 1 and len(args.input) > 1) or executor.kind == "ray"
    _METHOD.clear()
    work = [(p, o, args, not args.no_progress and not parallel) for p, o in zip(args.input, outs)]
    for text in map_files(
        _reconstruct_file, work, jobs, progress=not args.no_progress, desc="reconstruct", executor=executor
    ):
        print(text)
    return 0


_METHOD: dict[str, Any] = {}  # this process's method, built once for all its files


def _reconstruct_file(job: tuple[Path, Path, argparse.Namespace, bool]) -> str:
    """Reconstruct one input and write it; returns the summary (in this process or a
    ``--jobs`` worker)."""
    from engine.methods import run_method
    from engine.motion.retarget import manifest_fps, retarget, source_frames_needed
    from engine.motion.source_file import load_source
    from engine.studio.export import write_reconstruction
    from engine.tracking import simulate

    path, out, args, progress = job
    raw = load_source(path, source_frames_needed(args.max_frames), asf_path(args))  # a long file: only its start
    motion, report = retarget(raw, manifest_fps(path), rig_map=rig_map_path(args))
    if args.max_frames:
        motion = motion.slice(0, args.max_frames)
    if len(motion) == 0:
        raise UserError(f"{path}: the clip has no frames")
    if "method" not in _METHOD:
        _METHOD["method"] = build_method(args)
    tracking = simulate(motion, args.sensors, faulty=args.faulty, gaps=args.gaps, seed=args.seed)
    # comparison methods first: one that refuses the options (a --scene for IK) stops before the long run
    ghosts = run_ghosts(args, tracking, motion.skeleton, motion.name, progress, path.name, reference=motion)
    rec, results = run_method(
        _METHOD["method"], tracking, motion.skeleton, progress=progress, desc=path.name, light=True
    )
    rec.name = f"{motion.name} ({args.method})"
    write_reconstruction(
        out,
        rec,
        (raw, report) if args.on_source_rig else None,
        fps=args.fps,
        contents=export_contents(args, ghosts, tracking),
    )
    return summary(results, tracking, rec, out)


def summary(results: Sequence[Any], tracking: Any, rec: Any, out: Path) -> str:
    """Frames, ms/frame, iterations and the mean error of the connected trackers."""
    from engine import skeleton as sk

    ms = np.array([r.ms for r in results], float)
    iters = np.array([r.iterations for r in results], float)
    warnings = sum(len(r.warnings) for r in results)
    pos = rec.positions()
    idx = [sk.JOINT_INDEX[j] for j in tracking.joints]
    err = np.linalg.norm(pos[:, idx] - tracking.positions, axis=-1)
    tracked = err[tracking.connected]
    ee = f"{100 * tracked.mean():.2f} cm" if tracked.size else "-"
    lines = [
        f"wrote {out}",
        f"frames {len(results)}  ms/frame {ms.mean():.1f} (median {np.median(ms):.1f})  "
        f"iterations mean {iters.mean():.1f}  tracker error {ee}  warnings {warnings}",
    ]
    return "\n".join(lines)
