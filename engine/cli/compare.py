"""``dragposer-studio compare``: write docs/comparison.md, DragPoser beside SparsePoser,
RPM and the IK baseline on the validation files.

Four passes, each the same as ``evaluate --method A,B,...`` on the same simulated
trackers: preset ``6`` and ``3-head-hands``, each without and with RPM's hand-tracking
gaps (``--gaps``). In the passes with gaps DragPoser runs twice: with its trackers'
targets jumping (``sensor_blend=0``) and blended in over ``--blend`` seconds.
Every (pass, method) result is kept as JSON in ``--cache`` and reused when present, so
an interrupted run continues and the document can be rebuilt with ``--table-only``.
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path
from typing import Any

from engine.atomic import write_text
from engine.cli.comparison_doc import PASSES, render
from engine.cli.rig_options import add_rig_map_option, asf_path, rig_map_path
from engine.errors import UserError

DEFAULT_BLEND_S = 0.5


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "compare",
        help="write docs/comparison.md: DragPoser, SparsePoser, RPM and IK side by side",
        description=__doc__,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    p.add_argument(
        "paths",
        nargs="*",
        type=Path,
        metavar="PATH",
        help="BVH files or folders (default: the validation files of --data)",
    )
    p.add_argument("--data", type=Path, default=Path("prepared"), help="prepared folder listing the validation files")
    p.add_argument("--out", type=Path, default=Path("docs/comparison.md"), help="Markdown file to write")
    p.add_argument("--cache", type=Path, default=Path("runs/comparison"), help="folder of per-run JSON (reused)")
    p.add_argument("--max-frames", type=int, metavar="N", help="evaluate only the first N frames of each clip")
    p.add_argument(
        "--blend",
        type=float,
        default=DEFAULT_BLEND_S,
        metavar="S",
        help=f"DragPoser's blend time in the smoothed rows, seconds (default {DEFAULT_BLEND_S})",
    )
    p.add_argument("--passes", default="1,2,3,4", help="which passes to run, e.g. 3,4 (default: all)")
    p.add_argument("--only", metavar="A,B", help="run only these rows, e.g. dragposer,dragposer+blend (default: all)")
    p.add_argument("--table-only", action="store_true", help="only rebuild the document from the cache")
    p.add_argument("--no-progress", action="store_true", help="hide the progress bars")
    add_rig_map_option(p)
    p.set_defaults(func=_compare)


def _files(args: argparse.Namespace) -> list[Path]:
    from engine.cli.evaluate import find_clips
    from engine.training.data import read_manifest

    if args.paths:
        return find_clips(args.paths)
    return [Path(e["path"]) for e in read_manifest(args.data)["files"] if e["split"] == "val" and not e["mirrored"]]


def _run(args: argparse.Namespace, files: list[Path], preset: str, gaps: bool, variant: str) -> dict[str, Any]:
    from engine.cli.evaluate import json_safe_doc, run_method_on_clips
    from engine.motion.retarget import load_motion

    name = variant.split("+")[0]
    blend = args.blend if variant.endswith("+blend") else 0.0
    ns = argparse.Namespace(
        method=name,
        sensors=preset,
        mode="realtime",
        faulty=0.0,
        gaps=gaps,
        noise_pos=0.0,
        noise_rot=0.0,
        seed=0,
        no_progress=args.no_progress,
        iterations=None,
        lr=None,
        vae=None,
        predictor=None,
        set=[f"sensor_blend={blend}"] if name == "dragposer" else [],
    )
    motions = []
    for f in files:
        m = load_motion(f, rig_map=rig_map_path(args), asf=asf_path(args))
        motions.append((f, m.slice(0, args.max_frames) if args.max_frames else m))
    doc = json_safe_doc(run_method_on_clips(ns, name, motions))
    doc.update(variant=variant, gaps=gaps, max_frames=args.max_frames, blend_s=blend)
    return doc


def _key(preset: str, gaps: bool, variant: str) -> str:
    return f"{preset}{'-gaps' if gaps else ''}-{variant}.json"


def _cached(target: Path, gaps: bool) -> bool:
    """Whether ``target`` holds a usable result; a pass with gaps computed before PJ / AUJ
    followed FlowMDM (no ``pj_raw``) is stale and run again."""
    if not target.is_file():
        return False
    total = json.loads(target.read_text()).get("total", {})
    return not (gaps and "pj" in total and "pj_raw" not in total)


def _compare(args: argparse.Namespace) -> int:
    try:
        wanted = {int(x) for x in args.passes.split(",") if x.strip()}
    except ValueError as exc:
        raise UserError(f"--passes: expected numbers 1-4 separated by commas, got {args.passes!r}") from exc
    if not wanted <= {1, 2, 3, 4}:
        raise UserError(f"--passes: passes are numbered 1-4, got {args.passes!r}")
    args.cache.mkdir(parents=True, exist_ok=True)
    if not args.table_only:
        files = _files(args)
        for i, (preset, gaps, variants) in enumerate(PASSES, start=1):
            if i not in wanted:
                continue
            for v in variants:
                target = args.cache / _key(preset, gaps, v)
                if _cached(target, gaps) or (args.only and v not in args.only.split(",")):
                    continue
                print(f"pass {i}: {v} on preset {preset}{' with gaps' if gaps else ''}", flush=True)
                write_text(target, json.dumps(_run(args, files, preset, gaps, v), indent=2) + "\n")
    write_text(args.out, render(_load(args.cache), args))
    print(f"wrote {args.out}")
    return 0


def _load(cache: Path) -> dict[tuple[str, bool, str], dict[str, Any]]:
    out = {}
    for preset, gaps, variants in PASSES:
        for v in variants:
            f = cache / _key(preset, gaps, v)
            if f.is_file():
                out[(preset, gaps, v)] = json.loads(f.read_text())
    return out
