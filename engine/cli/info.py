"""``dragposer-studio info FILE.bvh``: what a BVH file holds and what it becomes."""

from __future__ import annotations

import argparse
import json
from pathlib import Path


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "info",
        help="describe a BVH file: detected rig, frames, fps, canonical result",
        description="Load a BVH file, detect its rig, retarget it to the canonical 22-joint "
        "skeleton at 60 fps and print what was found.",
    )
    p.add_argument("file", type=Path, help="BVH file")
    p.add_argument("--fps", type=float, help="true source frame rate (overrides the header)")
    p.add_argument("--json", action="store_true", help="print one JSON object instead of text")
    p.set_defaults(func=_info)


def _info(args: argparse.Namespace) -> int:
    from engine.retarget import load_with_report, manifest_fps

    motion, rep = load_with_report(args.file, args.fps or manifest_fps(args.file))
    out = {
        "file": str(args.file),
        "rig": rep.rig,
        "source_joints": rep.source_joints,
        "source_frames": rep.source_frames,
        "source_fps": rep.source_fps,
        "frames": len(motion),
        "fps": motion.fps,
        "joints": 22,
        "height_m": round(motion.skeleton.height(), 3),
    }
    if args.json:
        print(json.dumps(out))
        return 0
    print(f"file          {out['file']}")
    print(f"rig           {rep.rig}")
    print(f"source        {rep.source_joints} joints, {rep.source_frames} frames at {rep.source_fps:g} fps "
          f"({rep.source_frames / rep.source_fps:.2f} s)")
    print(f"canonical     22 joints, {len(motion)} frames at {motion.fps:g} fps ({motion.duration:.2f} s)")
    print(f"height        {out['height_m']:.2f} m (scale {rep.scale:.3f} of the canonical subject)")
    return 0
