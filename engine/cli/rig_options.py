"""``--rig-map MAP.toml``: the option every command that reads BVH files accepts."""

from __future__ import annotations

import argparse
from pathlib import Path

from engine.errors import UserError


def add_rig_map_option(parser: argparse.ArgumentParser) -> None:
    """Add ``--rig-map`` (a joint mapping written by ``rig suggest`` and edited by the user)."""
    parser.add_argument("--rig-map", type=Path, metavar="MAP.toml",
                        help="joint mapping for a rig that is not recognised (write one with "
                        "'dragposer-studio rig suggest FILE.bvh --out MAP.toml')")  # fmt: skip


def rig_map_path(args: argparse.Namespace) -> Path | None:
    """The ``--rig-map`` given, checked to exist."""
    path = getattr(args, "rig_map", None)
    if path is not None and not Path(path).is_file():
        raise UserError(f"--rig-map: no such file: {path}")
    return path
