"""``dragposer-studio data prepare``: build training shards from BVH folders."""

from __future__ import annotations

import argparse
from pathlib import Path

from engine.cli.rig_options import add_rig_map_option, rig_map_path
from engine.errors import UserError

REPO = Path(__file__).resolve().parents[2]
DEFAULT_DATA = REPO.parent / "shared" / "data"


def register(sub: argparse._SubParsersAction) -> None:
    data = sub.add_parser("data", help="prepare motion data for training")
    dsub = data.add_subparsers(dest="data_command", metavar="ACTION")
    p = dsub.add_parser(
        "prepare",
        help="retarget, mirror and split BVH files into training shards",
        description="Read every BVH under the given folders (default: ../shared/data), retarget "
        "it to the canonical skeleton, add mirrored copies, split train/val by file, compute "
        "normalisation statistics and write shards + manifest.json to --out. Unchanged inputs "
        "are not reprocessed.",
    )
    p.add_argument("inputs", nargs="*", type=Path, help="BVH or AMC files, or folders (default: ../shared/data)")
    p.add_argument("--out", type=Path, default=Path("prepared"), help="output folder (default: prepared)")
    p.add_argument(
        "--eval-only",
        action="append",
        metavar="GLOB",
        help="files matching GLOB (relative path) are kept out of training, split 'test' "
        "(default: dragposer/* and hdm05/*: AMASS-derived non-commercial, and CC BY-SA)",
    )
    p.add_argument("--no-mirror", action="store_true", help="do not add left/right mirrored copies")
    p.add_argument("--quiet", action="store_true", help="no progress bar")
    add_rig_map_option(p)
    p.set_defaults(func=_prepare)
    ls = dsub.add_parser(
        "list",
        help="print the source files of a split (e.g. to evaluate on the validation files)",
        description="Print one source BVH path per line for the given split of a prepared "
        "folder (original clips only, not mirrored copies).",
    )
    ls.add_argument("--data", type=Path, default=Path("prepared"), help="prepared folder (default: prepared)")
    ls.add_argument("--split", choices=("train", "val", "test"), default="val", help="split (default: val)")
    ls.set_defaults(func=_list)
    data.set_defaults(func=lambda args: data.print_help() or 0)


def _prepare(args: argparse.Namespace) -> int:
    from engine.data.prepare import prepare

    inputs = args.inputs or [DEFAULT_DATA]
    if not args.inputs and not DEFAULT_DATA.is_dir():
        raise UserError(f"no input given and the default data folder {DEFAULT_DATA} does not exist")
    res = prepare(
        inputs,
        args.out,
        eval_only=args.eval_only,
        mirror=not args.no_mirror,
        progress=not args.quiet,
        rig_map=rig_map_path(args),
    )
    state = "unchanged" if res.unchanged else "updated"
    print(
        f"{res.out}/manifest.json {state}: {res.written} shards written, {res.reused} reused, "
        f"{len(res.failed)} files failed"
    )
    for path, reason in res.failed:
        print(f"  failed: {path}: {reason}")
    return 1 if res.failed and not (res.written or res.reused) else 0


def _list(args: argparse.Namespace) -> int:
    from engine.training.data import read_manifest

    for entry in read_manifest(args.data)["files"]:
        if entry["split"] == args.split and not entry["mirrored"]:
            print(entry["path"])
    return 0
