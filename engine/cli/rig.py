"""``dragposer-studio rig suggest FILE.bvh --out MAP.toml``: a joint mapping to check and fix.

The file holds the automatic mapping (:mod:`engine.motion.rigs.automap`) with the reason
for every choice as a comment, the inferred unit and axes, and the joints that were
folded in or left out; pass it back with ``--rig-map MAP.toml`` after editing. When
the automatic mapping fails, a template with every canonical joint is written instead.
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

from engine.cli.rig_options import add_rig_map_option, rig_map_path


def register(sub: argparse._SubParsersAction) -> None:
    rig = sub.add_parser("rig", help="inspect how a BVH rig maps onto the canonical skeleton")
    rsub = rig.add_subparsers(dest="rig_command", metavar="ACTION")
    p = rsub.add_parser(
        "suggest",
        help="write the joint mapping guessed for a BVH file, with reasons, for you to fix",
        description="Map FILE.bvh's joints onto the 22 canonical joints and write the mapping as "
        "TOML (the --rig-map format), each guess with its reason.",
    )
    p.add_argument("file", type=Path, metavar="FILE.bvh", help="BVH file")
    p.add_argument("--out", type=Path, required=True, metavar="MAP.toml", help="mapping file to write")
    add_rig_map_option(p)
    p.set_defaults(func=_suggest)
    rig.set_defaults(func=lambda args: rig.print_help() or 0)


def _q(s: str) -> str:
    return json.dumps(str(s))  # a TOML basic string


def mapping_toml(prof, names: list[str]) -> str:
    """TOML text of a rig description (the ``--rig-map`` format) with its reasons as comments."""
    from engine import skeleton as sk

    why = prof.reasons
    lines = [
        f"# Joint mapping for {Path(prof.path).name}; check it, fix what is wrong, then pass",
        "# --rig-map THIS_FILE to any dragposer-studio command (or open it in the studio).",
        f"name = {_q(prof.name)}",
        f"description = {_q(prof.description)}",
        f"units_to_m = {prof.units_to_m!r}" + (f"  # {why['units_to_m']}" if "units_to_m" in why else ""),
    ]
    if "axes" in why:
        lines.append(f"# {why['axes']}")
    lines += [
        f"up = {_q(prof.up)}",
        f"forward = {_q(prof.forward)}",
        f"root_channels_relative_to_offset = {str(prof.root_channels_relative_to_offset).lower()}",
        f"skip_frames = {prof.skip_frames}",
        "",
        "[joints]  # canonical joint = source joint; leave out what the rig lacks",
    ]
    for c in sk.JOINT_NAMES:
        if c in prof.joints:
            note = why.get(c, "")
            if c in prof.folded:
                note += f"; folds in {', '.join(prof.folded[c])}"
            lines.append(f"{c} = {_q(prof.joints[c])}" + (f"  # {note.lstrip('; ')}" if note else ""))
        else:
            lines.append(f'# {c} = ""  # not found')
    lines += ["", '[landmarks]  # points for bone frames; "end:JOINT" = JOINT\'s end site']
    lines += [f"{k} = {_q(v)}" for k, v in prof.landmarks.items()]
    used = set(prof.joints.values()) | set(prof.landmarks.values())
    rest = [n for n in names if n not in used]
    lines += ["", f"# Joints not mapped ({len(rest)}), kept at their rest rotation on --on-source-rig:"]
    lines += [f"#   {', '.join(rest[i : i + 8])}" for i in range(0, len(rest), 8)]
    return "\n".join(lines) + "\n"


def template_toml(names: list[str], reason: str) -> str:
    """A mapping template when nothing could be mapped automatically."""
    from engine import skeleton as sk

    lines = [
        "# Automatic mapping failed:",
        *[f"#   {ln}" for ln in reason.splitlines()],
        "# Fill in the source joint of every canonical joint the rig has.",
        "# units_to_m, up and forward are inferred when left out.",
        "",
        "[joints]",
    ]
    lines += [f'# {c} = ""' for c in sk.JOINT_NAMES]
    lines += ["", f"# The file's {len(names)} joints:"]
    lines += [f"#   {', '.join(names[i : i + 8])}" for i in range(0, len(names), 8)]
    return "\n".join(lines) + "\n"


def write_suggestion(bvh: Path, out: Path, rig_map: Path | None = None) -> bool:
    """Write the mapping guessed for ``bvh`` to ``out`` (atomically); False when nothing could
    be mapped and a template to fill in was written instead. Used by ``rig suggest`` and
    the studio's Open dialog."""
    from engine.atomic import write_text
    from engine.errors import RigError
    from engine.motion.rigs import resolve_rig
    from engine.motion.source_file import load_source

    raw = load_source(bvh)
    try:
        text, ok = mapping_toml(resolve_rig(raw, rig_map), list(raw.names)), True
    except RigError as exc:
        text, ok = template_toml(list(raw.names), str(exc)), False
    write_text(out, text)
    return ok


def _suggest(args: argparse.Namespace) -> int:
    if write_suggestion(args.file, args.out, rig_map_path(args)):
        print(f"wrote {args.out}")
        return 0
    print(f"could not map {args.file} automatically; wrote a template to fill in: {args.out}")
    return 1
