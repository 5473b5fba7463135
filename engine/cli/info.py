"""``dragposer-studio info FILE.bvh``: what a BVH file holds and what it becomes."""

from __future__ import annotations

import argparse
import json
import math
from pathlib import Path

from engine.cli.rig_options import add_rig_map_option, asf_path, rig_map_path


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "info",
        help="describe a BVH file: detected rig, joint mapping, frames, fps, heights",
        description="Load a BVH file, detect or map its rig, retarget it to the canonical 22-joint "
        "skeleton at 60 fps and print what was found. With --json one JSON object is printed, "
        'with an "error" field when the file cannot be read.',
    )
    p.add_argument("file", type=Path, help="motion file: BVH, or AMC (its ASF found beside it or given by --asf)")
    p.add_argument("--fps", type=float, help="true source frame rate (overrides the header)")
    add_rig_map_option(p)
    p.add_argument("--json", action="store_true", help="print one JSON object instead of text")
    p.set_defaults(func=_info)


def describe(path: Path, fps: float | None = None, rig_map: Path | None = None, asf: Path | None = None) -> dict:
    """Everything ``info`` reports about a motion file (BVH or AMC), as a JSON-ready dict."""
    from engine.motion.retarget import CURRENT, load_with_report, manifest_fps
    from engine.validation import CLI, check_value

    if fps is not None:
        fps = check_value(CLI["fps"], fps, "--fps", "value")
    # only the start is kept (every row is still checked): a long file stays cheap
    motion, rep = load_with_report(path, fps or manifest_fps(path), rig_map, max_frames=1, strategy=CURRENT, asf=asf)

    def num(x: float, nd: int = 3):
        return round(float(x), nd) if math.isfinite(x) else None

    return {
        "file": str(path),
        "rig": rep.rig,
        "mapping": rep.mapping,
        "folded": rep.profile.folded if rep.profile else {},
        "up": rep.profile.up if rep.profile else None,
        "units_to_m": rep.profile.units_to_m if rep.profile else None,
        "source_joints": rep.source_joints,
        "source_frames": rep.source_frames,
        "source_fps": rep.source_fps,
        "frames": rep.frames,
        "fps": motion.fps,
        "joints": 22,
        "height_m": num(rep.height_m),
        "source_height_m": num(rep.source_height_m),
        "rest_height_m": num(motion.skeleton.height()),
        "scale": num(rep.scale),
        "retarget_version": rep.version,
        "skipped_frames": rep.skip,
        "body_twist": rep.body_joints or [],
        "rotations_copied": rep.copied,
        "source_twist": rep.source_twist_joints,
        "twist_rule": dict(rep.twist_rules or {}),
    }


def _info(args: argparse.Namespace) -> int:
    if args.json:
        try:
            out = describe(args.file, args.fps, rig_map_path(args), asf_path(args))
        except Exception as exc:  # noqa: BLE001 - --json promises one object whatever happens
            print(json.dumps({"file": str(args.file), "error": str(exc) or type(exc).__name__}))
            return 2
        print(json.dumps(out))
        return 0
    out = describe(args.file, args.fps, rig_map_path(args), asf_path(args))
    print(f"file          {out['file']}")
    print(f"rig           {out['rig']} (up {out['up']}, {out['units_to_m']:g} m per unit)")
    print(
        f"source        {out['source_joints']} joints, {out['source_frames']} frames at {out['source_fps']:g} fps "
        f"({out['source_frames'] / out['source_fps']:.2f} s)"
    )
    print(f"canonical     22 joints, {out['frames']} frames at {out['fps']:g} fps ({out['frames'] / out['fps']:.2f} s)")
    print(
        f"height        {out['height_m']:.2f} m (source {out['source_height_m']:.2f} m; "
        f"T-pose {out['rest_height_m']:.2f} m, legs {out['scale']:.3f} x the canonical subject's)"
    )
    print("mapping       " + ", ".join(f"{c}={s}" for c, s in out["mapping"].items()))
    if out["rotations_copied"]:
        print("rotations     copied as they are (the rig's rotations are canonical ones: align = false)")
    if out["source_twist"]:
        print(
            "source twist  " + ", ".join(out["source_twist"]) + " (the rig lacks the points that define "
            "their twist: docs/skeleton.md, Body-defined twist)"
        )
    if out["twist_rule"]:
        print(
            "twist rule    " + ", ".join(f"{j} ({r})" for j, r in out["twist_rule"].items()) + " (the rig lacks "
            "the points that define their twist; a documented rule stands in: docs/skeleton.md, Body-defined twist)"
        )
    if out["folded"]:
        print("folded in     " + ", ".join(f"{c}: {'+'.join(v)}" for c, v in out["folded"].items()))
    return 0
