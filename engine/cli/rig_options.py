"""``--rig-map MAP.toml`` and ``--asf SKELETON.asf``: the options every command that reads
motion files (BVH, or AMC with its ASF skeleton) accepts."""

from __future__ import annotations

import argparse
from pathlib import Path

from engine.errors import UserError


def add_rig_map_option(parser: argparse.ArgumentParser) -> None:
    """Add ``--rig-map`` (a joint mapping written by ``rig suggest`` and edited by the user)
    and ``--asf`` (the skeleton of AMC motions, when it is not found beside them)."""
    parser.add_argument(
        "--rig-map",
        type=Path,
        metavar="MAP.toml",
        help="joint mapping for a rig that is not recognised (write one with "
        "'dragposer-studio rig suggest FILE.bvh --out MAP.toml')",
    )
    parser.add_argument(
        "--asf",
        type=Path,
        metavar="SKELETON.asf",
        help="ASF skeleton of .amc motions (default: the data manifest's, or the ASF "
        "beside the motion whose name starts the motion's)",
    )


def rig_map_path(args: argparse.Namespace) -> Path | None:
    """The ``--rig-map`` given, checked to exist."""
    path = getattr(args, "rig_map", None)
    if path is not None and not Path(path).is_file():
        raise UserError(f"--rig-map: no such file: {path}")
    return path


def asf_path(args: argparse.Namespace) -> Path | None:
    """The ``--asf`` given, checked to exist."""
    path = getattr(args, "asf", None)
    if path is not None and not Path(path).is_file():
        raise UserError(f"--asf: no such file: {path}")
    return path
