"""Output options shared by the commands that write motion files (``reconstruct``,
``convert``, ``bake``): the format follows ``--out``'s extension (``.bvh``, ``.glb``,
``.gltf``; :mod:`engine.motion.formats`), and what a glTF file holds besides the main
character: ``--no-mesh``, ``--ghosts METHOD,...`` (comparison characters) and
``--tracker-nodes`` (the tracker targets as animated boxes). docs/export.md.
"""

from __future__ import annotations

import argparse
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from engine.errors import UserError
from engine.motion.formats import GLTF_SUFFIXES, MOTION_FORMATS, GltfContents, motion_format


def add_export_options(
    p: argparse.ArgumentParser, ghosts: bool = False, tracker_nodes: bool = False, out_dir: bool = False
) -> None:
    """Add ``--no-mesh`` and, where the command has trackers to show, ``--ghosts`` and
    ``--tracker-nodes``; with ``out_dir``, ``--out-format`` (the extension of the files
    written to ``--out-dir``)."""
    g = p.add_argument_group("glTF output (OUT ending in .glb or .gltf; docs/export.md)")
    if out_dir:
        g.add_argument(
            "--out-format",
            choices=[e[1:] for e in MOTION_FORMATS],
            default="bvh",
            help="format of the files written to --out-dir (default: bvh)",
        )
    g.add_argument(
        "--no-mesh",
        action="store_true",
        help="leave the skinned mannequin out of the glTF file (skeleton and animation only)",
    )
    if ghosts:
        g.add_argument(
            "--ghosts",
            metavar="METHOD,...",
            default="",
            help="add these methods' reconstructions from the same trackers as extra characters, e.g. ik,sparseposer",
        )
    if tracker_nodes:
        g.add_argument(
            "--tracker-nodes",
            action="store_true",
            help="add the tracker targets as animated boxes (scaled to 0 while a tracker is lost)",
        )


def ghost_methods(args: argparse.Namespace) -> tuple[str, ...]:
    """The method names of ``--ghosts`` (empty when not given)."""
    return tuple(n.strip() for n in (getattr(args, "ghosts", "") or "").split(",") if n.strip())


def check_export(
    args: argparse.Namespace, outs: Sequence[Path], flag: str = "--out", hint: str = "give --out a .glb or .gltf name"
) -> None:
    """Refuse, before any work, an output whose extension no writer knows and glTF-only
    options with a BVH output (the message ends with ``hint``); check the ``--ghosts``
    names against the registry."""
    for out in outs:
        motion_format(out, flag)
    extras = [f"--{k.replace('_', '-')}" for k in ("no_mesh", "tracker_nodes") if getattr(args, k, False)]
    if ghost_methods(args):
        extras.append("--ghosts")
    if extras and not all(Path(o).suffix.lower() in GLTF_SUFFIXES for o in outs):
        verb = "apply" if len(extras) > 1 else "applies"
        raise UserError(f"{' and '.join(extras)} {verb} to glTF output: {hint} (a BVH file holds one skeleton)")
    if ghost_methods(args):
        from engine.methods import available_methods

        known = available_methods()
        for name in ghost_methods(args):
            if name not in known:
                raise UserError(f"--ghosts: unknown method {name!r}; available: {', '.join(known)}")


def export_contents(
    args: argparse.Namespace, ghosts: tuple[tuple[str, Any], ...] = (), tracking: Any = None
) -> GltfContents:
    """What the glTF file holds: the mesh unless ``--no-mesh``, ``ghosts`` and, with
    ``--tracker-nodes``, ``tracking``."""
    return GltfContents(
        mesh=not getattr(args, "no_mesh", False),
        ghosts=tuple(ghosts),
        tracking=tracking if getattr(args, "tracker_nodes", False) else None,
    )


_GHOSTS: dict[str, Any] = {}  # this process's comparison methods, built once for all its files


def run_ghosts(
    args: argparse.Namespace, tracking: Any, skeleton: Any, clip: str, progress: bool, desc: str, reference: Any = None
) -> tuple[tuple[str, Any], ...]:
    """Reconstruct ``tracking`` on ``skeleton`` with every ``--ghosts`` method (the same
    model and mode options as the main method; ``reference``, the clip, for a method that
    needs ground truth); returns ``(name, Motion)`` pairs for :func:`export_contents`,
    each named ``"<clip> (<method>)"``."""
    from engine.cli.method_options import build_method
    from engine.methods import run_method

    out = []
    for name in ghost_methods(args):
        if name not in _GHOSTS:
            _GHOSTS[name] = build_method(argparse.Namespace(**{**vars(args), "method": name}))
        motion, _ = run_method(
            _GHOSTS[name],
            tracking,
            skeleton,
            progress=progress,
            reference=reference,
            desc=f"{desc} ({name})",
            light=True,
        )
        motion.name = f"{clip} ({name})"
        out.append((name, motion))
    return tuple(out)
