"""``dragposer-studio convert IN.bvh --out OUT.bvh``: a BVH retargeted to the canonical skeleton,
written as BVH or glTF by ``--out``'s extension (docs/export.md)."""

from __future__ import annotations

import argparse
from pathlib import Path

from engine.cli.export_options import add_export_options, check_export, export_contents
from engine.cli.rig_options import add_rig_map_option, asf_path, rig_map_path


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "convert",
        help="retarget a BVH file to the canonical 22-joint skeleton and save it as BVH",
        description="Load IN.bvh on any humanoid rig, retarget it to the canonical skeleton with the "
        "subject's own proportions, resample it (60 fps by default) and write OUT.bvh atomically.",
    )
    p.add_argument("input", type=Path, metavar="IN.bvh", help="source motion")
    p.add_argument(
        "--out",
        type=Path,
        required=True,
        metavar="OUT.bvh",
        help="where to write the canonical clip: .bvh, .glb or .gltf (docs/export.md)",
    )
    add_rig_map_option(p)
    p.add_argument("--fps", type=float, metavar="F", help="output frame rate (default: 60)")
    p.add_argument("--source-fps", type=float, metavar="F", help="true frame rate of IN.bvh (overrides its header)")
    add_export_options(p)
    p.set_defaults(func=_convert)


def _convert(args: argparse.Namespace) -> int:
    from engine.errors import UserError
    from engine.motion.formats import save_motion
    from engine.motion.retarget import CURRENT, load_with_report, manifest_fps, resample_motion

    if args.fps is not None and not args.fps > 0:
        raise UserError(f"--fps must be > 0, got {args.fps}")
    check_export(args, [args.out])
    motion, rep = load_with_report(
        args.input,
        args.source_fps or manifest_fps(args.input),
        rig_map_path(args),
        strategy=CURRENT,
        asf=asf_path(args),
    )
    if args.fps:
        motion = resample_motion(motion, args.fps)
    save_motion(args.out, motion, contents=export_contents(args))
    print(
        f"wrote {args.out}: rig {rep.rig}, {len(motion)} frames at {motion.fps:g} fps, "
        f"height {rep.height_m:.2f} m (source {rep.source_height_m:.2f} m)"
    )
    return 0
