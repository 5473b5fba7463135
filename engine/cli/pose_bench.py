"""``dragposer-studio bench --pose-tasks``: the pose-mode benchmark's report
(:mod:`engine.authoring.pose_tasks`): a table, and ``--json``."""

from __future__ import annotations

import argparse
import json
import os
import platform
from pathlib import Path

from engine.errors import UserError


def add_options(p: argparse.ArgumentParser) -> None:
    """The ``--pose-tasks`` mode's options on the ``bench`` parser."""
    from engine.authoring.pose_task_table import EVENTS, RELEASES, TASK_NAMES

    g = p.add_argument_group(
        "pose tasks",
        "with --pose-tasks: posing tasks on the character, no clip "
        "(--method names the posers: pose-mode, ik, and bake, each task's one-key scene "
        "baked as `bake` bakes it; default all three)",
    )
    g.add_argument("--pose-tasks", action="store_true", help="run the pose-mode benchmark instead of timing methods")
    g.add_argument("--task", action="append", choices=TASK_NAMES, help="task to run; repeat for several (default: all)")
    g.add_argument(
        "--release",
        choices=RELEASES,
        default="none",
        help="at each drag's end: none (as the pose window) or settle (Edit > Settle pose)",
    )
    g.add_argument("--events", type=int, default=EVENTS, help=f"drag events per drag (default: {EVENTS})")
    g.add_argument(
        "--set",
        dest="pose_set",
        action="append",
        default=[],
        metavar="NAME=VALUE",
        help="pose-mode option: a PoseMode keyword, or solve.NAME / settle.NAME for its solves",
    )
    ref = g.add_mutually_exclusive_group()
    ref.add_argument(
        "--reference",
        type=Path,
        metavar="DIR",
        help="naturalness against the 9 validation files read from this mocap folder (e.g. "
        "../shared/data/mocap) instead of the poses shipped from them",
    )
    ref.add_argument(
        "--reference-data",
        type=Path,
        metavar="PREPARED",
        help="naturalness against the val split of this prepared folder (default: ./prepared when it "
        "has a manifest, else the validation files' poses shipped in assets/reference/)",
    )
    ref.add_argument(
        "--reference-files",
        type=Path,
        nargs="+",
        metavar="FILE",
        help="naturalness against these motion files instead (BVH or ASF/AMC, one take each, e.g. "
        "another lab's clips that hold the poses a task asks for)",
    )
    g.add_argument(
        "--reference-stride",
        type=int,
        default=4,
        help="every Nth reference frame (default: 4; a multiple of 4 with the shipped poses)",
    )


def run(args: argparse.Namespace, default_clip: Path) -> int:
    """The benchmark of ``args`` (``bench --pose-tasks``); prints the table."""
    import torch

    from engine.atomic import write_text
    from engine.authoring.pose_mode import PoseMode
    from engine.authoring.pose_task_table import BAKE, EVENTS
    from engine.authoring.pose_tasks import POSERS, run_bake, run_task, select_tasks, split_options
    from engine.models import load_default_models
    from engine.validation import check_output_path

    if args.file != default_clip:
        raise UserError("--pose-tasks poses the character and reads no clip; leave out the file")
    if args.json:
        check_output_path(args.json, "--json")
    every = [*POSERS, BAKE]
    posers = args.method or every
    unknown = [m for m in posers if m not in every]
    if unknown:
        raise UserError(f"--pose-tasks: unknown poser(s) {', '.join(unknown)}; posers: {', '.join(every)}")
    init = split_options(args.pose_set)[0]  # bad options fail before the models load
    # the bake poses as the pose window does (EVENTS drag events, no settle) with the scene's pose options
    unlike = (
        [f"--events {args.events}"] * (args.events != EVENTS)
        + [f"--release {args.release}"] * (args.release != "none")
        + [f"--set {o}" for o in args.pose_set if not _pose_option(o)]
    )
    if BAKE in posers and unlike:
        if args.method:
            raise UserError(
                f"--pose-tasks: the bake rows pose as `bake` does ({EVENTS} drag events, no settle, "
                f"pose options only); {', '.join(unlike)} do not apply to them: leave out "
                f"--method {BAKE}"
            )
        posers = [p for p in posers if p != BAKE]
    left_out = BAKE not in posers and not args.method
    tasks = select_tasks(args.task)
    vae = load_default_models().vae
    offsets = PoseMode(vae, **init).character.skeleton.offsets
    reference = _reference(args, offsets)
    spread = reference.spread_summary()
    rows = [
        run_bake(t, vae, reference, init.get("options"))
        if p == BAKE
        else run_task(t, p, vae, reference, args.pose_set, args.release, args.events)
        for t in tasks
        for p in posers
    ]
    machine = {"cpu_count": os.cpu_count(), "torch_threads": torch.get_num_threads(), "platform": platform.platform()}
    options = " ".join(args.pose_set) or "defaults"
    print(
        f"pose tasks: release {args.release}, {args.events} events per drag, pose mode {options}; "
        f"{machine['cpu_count']} cores, torch {machine['torch_threads']} threads"
    )
    if left_out:
        print(f"bake rows left out: they pose as `bake` does ({EVENTS} drag events, no settle, pose options only)")
    print(
        f"naturalness reference: {reference.description}, {len(reference)} poses; real poses' nearest other "
        f"take: median {spread['median_cm']:.1f} cm, p95 {spread['p95_cm']:.1f} cm"
    )
    print(_table(rows))
    if args.json:
        out = {
            "release": args.release,
            "events": args.events,
            "options": args.pose_set,
            "machine": machine,
            "reference": {"description": reference.description, "poses": len(reference), **spread},
            "tasks": [r.to_dict() for r in rows],
        }
        write_text(args.json, json.dumps(out, indent=1))
    return 0


def _pose_option(item: str) -> bool:
    """Whether ``--set`` ``item`` sets a :class:`PoseOptions` field (what a scene stores)."""
    import dataclasses

    from engine.authoring.pose_options import PoseOptions

    return item.split("=", 1)[0].strip() in {f.name for f in dataclasses.fields(PoseOptions)}


def _reference(args: argparse.Namespace, offsets):
    from engine.authoring import pose_reference as R

    if args.reference is not None:
        if not Path(args.reference).is_dir():
            raise UserError(
                f"--reference {args.reference}: not a folder (give the mocap folder that holds "
                f"{R.VALIDATION_FILES[0]} and the other validation files)"
            )
        try:
            files = R.validation_files(args.reference)
        except UserError as exc:
            raise UserError(f"--reference {args.reference}: {exc}") from None
        return R.load_files(files, offsets, args.reference_stride)
    if args.reference_files:
        missing = [str(p) for p in args.reference_files if not Path(p).is_file()]
        if missing:
            raise UserError(f"--reference-files: no such file: {', '.join(missing)}")
        if len(args.reference_files) < 2:
            raise UserError("--reference-files: give at least two takes (the spread of real poses compares takes)")
        return R.load_files(args.reference_files, offsets, args.reference_stride, "files")
    data = args.reference_data
    if data is None and (Path("prepared") / "manifest.json").is_file():
        data = Path("prepared")
    if data is not None:
        return R.load_prepared(data, offsets, args.reference_stride)
    return R.load_shipped(offsets, args.reference_stride)


def _table(rows) -> str:
    from engine.authoring.pose_reference import take_label

    head = (
        f"{'task':<15} {'poser':<9} {'drags':>5} {'err cm':>7} {'turn':>5} {'reach':>5} {'natural':>7} "
        f"{'spread':>6} {'limits':>6} {'feet':>5} {'balance':>7} {'tilt':>5} {'slide':>5} {'knee':>5} {'s':>5}  nearest take"
    )
    lines = [head]
    for r in rows:
        c = r.check
        err, turn = r.max_position_error_cm, r.max_turn_error_deg
        feet = "".join(side[0].upper() if down else "-" for side, down in c.feet_down.items())
        slide = max(r.feet_moved_cm.values()) if r.feet_moved_cm else None
        lines.append(
            f"{r.task:<15} {r.poser:<9} {r.drags:>2}/{r.allowed:<2} {_num(err, 7, 1)} {_num(turn, 5, 0)} "
            f"{'yes' if r.reached else 'no':>5} {r.naturalness_cm:>7.1f} {'in' if r.within_spread else 'out':>6} "
            f"{len(c.violations):>6d} {feet:>5} {_num(c.balance_margin_cm, 7, 1)} {c.trunk_tilt_deg:>5.0f} "
            f"{_num(slide, 5, 0)} {_num(r.knee_height_cm, 5, 0)} {r.seconds:>5.1f}  {take_label(r.nearest_take)}"
        )
    lines.append(
        "err cm: largest position error; turn: deg; natural: cm to the nearest real pose (spread: within "
        "the real poses' 95th percentile); limits: knees/elbows hyperextended; feet: L/R down; balance: cm "
        "inside the support polygon (both feet down); tilt: trunk from vertical, deg; slide: cm an undragged "
        "ankle slid; knee: cm from the floor to the lower knee joint; s: seconds of posing (bake: of the "
        "bake); nearest take: the reference take the nearest real pose comes from; bake: the task's one-key "
        "scene (assets/scenes/pose_tasks) baked as `bake` bakes it"
    )
    return "\n".join(lines)


def _num(x: float | None, width: int, digits: int) -> str:
    return f"{'-':>{width}}" if x is None else f"{x:>{width}.{digits}f}"
