"""Options shared by ``live`` and ``reconstruct --trackers``: the tracker mapping,
calibration and the optional ground-truth clip, and the skeleton they imply."""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import Any

from engine.errors import UserError


def add_tracker_options(p: argparse.ArgumentParser) -> None:
    p.add_argument(
        "--map",
        default="",
        metavar="MAPPING",
        help="tracker name -> joint, e.g. head=upperneck,puck1=root,puck2=lankle:3, or a JSON "
        "file (default: head, left_hand, right_hand, hips, left_foot, right_foot; docs/trackers.md)",
    )
    p.add_argument(
        "--calibrate",
        type=float,
        default=0.0,
        metavar="SECONDS",
        help="calibrate height, arm span and tracker offsets from the first SECONDS of the stream "
        "(stand still, T-pose or standing)",
    )
    p.add_argument(
        "--calibration-pose",
        choices=("auto", "tpose", "standing"),
        default="auto",
        help="pose held while calibrating (default: detected)",
    )
    p.add_argument(
        "--reference",
        type=Path,
        metavar="CLIP.bvh",
        help="ground-truth clip (e.g. the one `send` streamed): its skeleton is used unless "
        "calibrating, and the error against it is reported",
    )
    p.add_argument("--json", type=Path, metavar="STATS.json", help="write the figures as JSON")


def check_tracker_options(args: argparse.Namespace) -> None:
    """Fail on bad values before any work starts."""
    import math

    if not (math.isfinite(args.calibrate) and 0.0 <= args.calibrate <= 60.0):
        raise UserError(f"--calibrate must be seconds in [0, 60], got {args.calibrate}")
    if args.reference is not None and not args.reference.is_file():
        raise UserError(f"--reference {args.reference}: no such file")
    for name in ("out", "json", "record"):
        path = getattr(args, name, None)
        if path is not None and path.is_dir():
            raise UserError(f"--{name} {path}: is a directory")
        if path is not None and not path.parent.exists():
            raise UserError(f"--{name} {path}: folder {path.parent} does not exist")


def load_reference(args: argparse.Namespace) -> Any:
    if args.reference is None:
        return None
    from engine.cli.rig_options import asf_path, rig_map_path
    from engine.motion.retarget import load_motion

    return load_motion(args.reference, rig_map=rig_map_path(args), asf=asf_path(args))


def default_skeleton(reference: Any) -> Any:
    """The reference clip's skeleton, else the canonical one."""
    from engine import skeleton as sk

    return reference.skeleton if reference is not None else sk.Skeleton.canonical()


def write_json(path: Path | None, stats: dict) -> None:
    if path is None:
        return
    import json

    from engine.atomic import write_text

    write_text(path, json.dumps(stats, indent=2) + "\n")
