"""``dragposer-studio evaluate PATH...``: metrics of a method on simulated trackers.

Every clip is loaded onto the canonical skeleton, trackers are simulated from it
(:func:`engine.tracking.simulate`), the method reconstructs it frame by frame and the
metrics of :mod:`engine.metrics` (see ``docs/metrics.md``) compare the result with the
clip. One table row per file plus a frame-weighted total; ``--json`` writes the same
numbers atomically. Files are evaluated in ``--jobs`` worker processes (default: one
per core; :mod:`engine.cli.jobs`), each file by every method named, and the results
are merged in file order: the same numbers as a serial run.
"""

from __future__ import annotations

import argparse
import json
import math
from collections.abc import Iterable
from pathlib import Path
from typing import Any

import numpy as np

from engine.atomic import write_text
from engine.cli.jobs import add_jobs_option, executor_of, jobs_of, map_files
from engine.cli.method_options import add_model_options, apply_settings, method_kwargs
from engine.cli.rig_options import add_rig_map_option, asf_path, rig_map_path
from engine.errors import UserError
from engine.solver.settings import MODES

#: Columns of the printed table: (metric key, header, format).
COLUMNS = (
    ("frames", "frames", "{:>7d}"),
    ("pos_cm", "Pos cm", "{:>7.2f}"),
    ("rot_deg", "Rot deg", "{:>7.2f}"),
    ("vel_cms", "Vel cm/s", "{:>8.2f}"),
    ("ee_cm", "EE cm", "{:>7.2f}"),
    ("jitter", "Jitter", "{:>7.2f}"),
    ("gt_jitter", "GT jit", "{:>7.2f}"),
    ("ms_per_frame", "ms/frame", "{:>8.2f}"),
)
GAP_COLUMNS = (("pj", "PJ", "{:>7.2f}"), ("auj", "AUJ", "{:>8.1f}"))


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "evaluate",
        help="reconstruct clips from simulated trackers and report Pos/Rot/Vel/EE/Jitter",
        description="Simulate trackers from each clip, reconstruct it with a method and compare "
        "with the clip. Metrics are defined in docs/metrics.md.",
    )
    p.add_argument("paths", nargs="+", type=Path, metavar="PATH", help="BVH files or folders (searched for *.bvh)")
    p.add_argument(
        "--method",
        default="ik",
        help="reconstruction method, or several separated by commas to compare them on the same "
        "simulated trackers, e.g. dragposer,ik,sparseposer,rpm (default: ik)",
    )
    p.add_argument("--sensors", default="6", help="sensor preset or list, e.g. 6, 4, root,lwrist:3 (default: 6)")
    p.add_argument(
        "--faulty",
        type=float,
        default=0.0,
        metavar="P",
        help="per-frame probability that one sensor fails for 100 frames (DragPoser: 0.01)",
    )
    p.add_argument("--gaps", action="store_true", help="simulate RPM's hand-tracking gaps; adds PJ/AUJ")
    p.add_argument("--noise-pos", type=float, default=0.0, metavar="M", help="position noise std, metres")
    p.add_argument("--noise-rot", type=float, default=0.0, metavar="DEG", help="rotation noise std, degrees")
    p.add_argument("--mode", choices=MODES, default="realtime", help="passed to the method")
    p.add_argument("--iterations", type=int, metavar="N", help="optimizer iterations per frame (passed to the method)")
    p.add_argument("--lr", type=float, help="optimizer learning rate (latent-space methods)")
    add_model_options(p)
    p.add_argument("--max-frames", type=int, metavar="N", help="evaluate only the first N frames of each clip")
    p.add_argument("--seed", type=int, default=0, help="seed of the tracker simulation (default: 0)")
    p.add_argument(
        "--json",
        type=Path,
        metavar="OUT.json",
        help="also write the results as JSON (several methods: an object per method name)",
    )
    p.add_argument("--markdown", type=Path, metavar="OUT.md", help="also write the table as Markdown")
    p.add_argument("--no-progress", action="store_true", help="hide the progress bars")
    add_rig_map_option(p)
    add_jobs_option(p)
    p.set_defaults(func=_evaluate)


def find_clips(paths: Iterable[Path]) -> list[Path]:
    """BVH files named directly or found (recursively) in folders, in a stable order."""
    out: list[Path] = []
    for p in paths:
        if p.is_dir():
            found = sorted(f for f in p.rglob("*") if f.is_file() and f.suffix.lower() == ".bvh")
            if not found:
                raise UserError(f"{p}: no .bvh files in this folder")
            out.extend(found)
        elif p.is_file():
            out.append(p)
        else:
            raise UserError(f"{p}: no such file or folder")
    return list(dict.fromkeys(out))


def evaluate_clip(
    motion: Any,
    method: Any,
    preset: str,
    *,
    faulty: float = 0.0,
    gaps: bool = False,
    noise_pos_m: float = 0.0,
    noise_rot_deg: float = 0.0,
    seed: int = 0,
    progress: bool = True,
    desc: str | None = None,
) -> dict[str, float | int | list[float]]:
    """Metrics of ``method`` on one canonical clip (what the command runs per file).

    Returns
    -------
    dict
        The keys of :func:`engine.metrics.evaluate_motion` plus ``iterations_mean`` and
        ``ms_per_frame``; ``latent_step`` (mean distance between consecutive frames'
        latents) for latent-space methods; PJ / AUJ keys only when trackers can be lost (``gaps`` or
        ``faulty``).
    """
    from engine.methods import run_method
    from engine.metrics import evaluate_motion
    from engine.tracking import simulate

    tracking = simulate(
        motion, preset, noise_pos_m=noise_pos_m, noise_rot_deg=noise_rot_deg, faulty=faulty, gaps=gaps, seed=seed
    )
    rec, results = run_method(
        method, tracking, motion.skeleton, progress=progress, reference=motion, desc=desc, light=True
    )
    lossy = gaps or faulty > 0
    out = evaluate_motion(motion, rec, tracking.connected if lossy else None)
    out["iterations_mean"] = float(np.mean([r.iterations for r in results]))
    out["ms_per_frame"] = float(np.mean([r.ms for r in results]))
    latents = [r.latent for r in results]
    if len(latents) > 1 and all(z is not None for z in latents):
        z = np.asarray(latents, dtype=np.float64)
        out["latent_step"] = float(np.linalg.norm(np.diff(z, axis=0), axis=-1).mean())
    return out


def _json_safe(d: dict[str, Any]) -> dict[str, Any]:
    """NaN / inf become null: strict JSON readers reject the bare tokens."""
    return {k: (None if isinstance(v, float) and not math.isfinite(v) else v) for k, v in d.items()}


def format_table(per_file: dict[str, dict[str, Any]], total: dict[str, Any], lossy: bool) -> str:
    cols = COLUMNS + (GAP_COLUMNS if lossy else ())
    width = max([len("total"), *(len(k) for k in per_file)])
    lines = [f"{'clip':<{width}}  " + " ".join(f"{h:>{len(fmt.format(0))}}" for _, h, fmt in cols)]

    def row(name: str, m: dict[str, Any]) -> str:
        cells = []
        for key, _, fmt in cols:
            v = m.get(key)
            w = len(fmt.format(0))
            cells.append(f"{'-':>{w}}" if v is None or (isinstance(v, float) and math.isnan(v)) else fmt.format(v))
        return f"{name:<{width}}  " + " ".join(cells)

    lines += [row(k, v) for k, v in per_file.items()]
    lines.append(row("total", total))
    return "\n".join(lines)


def format_markdown(rows: dict[str, dict[str, Any]], lossy: bool, first: str = "clip") -> str:
    """The table as Markdown: one row per entry of ``rows`` (files or methods)."""
    cols = COLUMNS + (GAP_COLUMNS if lossy else ())
    out = [f"| {first} | " + " | ".join(h for _, h, _ in cols) + " |", "|---|" + "---:|" * len(cols)]
    for name, m in rows.items():
        cells = []
        for key, _, fmt in cols:
            v = m.get(key)
            cells.append("-" if v is None or (isinstance(v, float) and math.isnan(v)) else fmt.format(v).strip())
        out.append(f"| {name} | " + " | ".join(cells) + " |")
    return "\n".join(out) + "\n"


def method_names(spec: str) -> list[str]:
    """``"dragposer, ik"`` -> ``["dragposer", "ik"]``; unknown or repeated names fail early."""
    from engine.methods import available_methods

    names = [n.strip() for n in spec.split(",") if n.strip()]
    if not names:
        raise UserError("--method: no method named")
    for n in names:
        if n not in available_methods():
            raise UserError(f"--method: unknown method {n!r}; available: {', '.join(available_methods())}")
    if len(set(names)) != len(names):
        raise UserError(f"--method: a method is named twice in {spec!r}")
    return names


_METHODS: dict[str, Any] = {}  # this process's methods, built once for all its files


def _method(args: argparse.Namespace, name: str) -> Any:
    from engine.methods import Configurable, get_method

    if name not in _METHODS:
        method = get_method(name, **method_kwargs(args, args.mode, name))
        if isinstance(method, Configurable) or len(args.method.split(",")) == 1:
            apply_settings(method, name, args.set)
        _METHODS[name] = method
    return _METHODS[name]


def _evaluate_clip_with(args: argparse.Namespace, name: str, path: Path, motion: Any, progress: bool) -> dict:
    return evaluate_clip(
        motion,
        _method(args, name),
        args.sensors,
        faulty=args.faulty,
        gaps=args.gaps,
        noise_pos_m=args.noise_pos,
        noise_rot_deg=args.noise_rot,
        seed=args.seed,
        progress=progress,
        desc=f"{name} {path.name}",
    )


def _doc(args: argparse.Namespace, name: str, per_file: dict[str, Any]) -> dict[str, Any]:
    from engine.metrics import summarize

    return {"method": name, "preset": args.sensors, "mode": args.mode, "total": summarize(per_file), "files": per_file}


def run_method_on_clips(args: argparse.Namespace, name: str, motions: list[tuple[Path, Any]]) -> dict[str, Any]:
    """Evaluate one method on the loaded clips (in this process): the single-method JSON object."""
    _METHODS.clear()
    return _doc(args, name, {str(p): _evaluate_clip_with(args, name, p, m, not args.no_progress) for p, m in motions})


def _evaluate_file(job: tuple[Path, argparse.Namespace, list[str], bool]) -> dict[str, Any]:
    """Every method's metrics on one file, or ``{"error": message}`` for a method that
    cannot run it (in this process or a ``--jobs`` worker)."""
    from engine.motion.retarget import load_motion

    path, args, names, progress = job
    motion = load_motion(
        path, rig_map=rig_map_path(args), asf=asf_path(args), max_frames=args.max_frames
    )  # reads only what is needed
    if len(motion) < 4:
        raise UserError(f"{path}: only {len(motion)} frames; at least 4 are needed")
    out: dict[str, Any] = {}
    for name in names:
        try:
            out[name] = _evaluate_clip_with(args, name, path, motion, progress)
        except UserError as exc:  # e.g. a method that needs another sensor preset
            if len(names) == 1:
                raise
            out[name] = {"error": str(exc)}
    return out


def json_safe_doc(doc: dict[str, Any]) -> dict[str, Any]:
    """A copy of one method's evaluation ``doc`` whose totals and per-file figures JSON can write."""
    out = dict(doc)
    if "total" in out:
        out["total"] = _json_safe(out["total"])
        out["files"] = {k: _json_safe(v) for k, v in out["files"].items()}
    return out


def _evaluate(args: argparse.Namespace) -> int:
    from engine.tracking import parse_sensors
    from engine.validation import check_args, check_output_path

    parse_sensors(args.sensors)  # fail before loading anything
    names = method_names(args.method)
    check_args(args)
    if args.json:
        check_output_path(args.json, "--json")
    if args.max_frames is not None and args.max_frames < 4:
        raise UserError("--max-frames must be at least 4 (jitter needs 4 frames)")
    clips = find_clips(args.paths)
    jobs, executor = jobs_of(args), executor_of(args)
    # workers (or Ray tasks): one bar for the files
    progress = not args.no_progress and executor.kind == "local" and (jobs == 1 or len(clips) == 1)
    _METHODS.clear()
    if len(names) == 1 and (executor.kind == "ray" or (jobs > 1 and len(clips) > 1)):
        # A bad model file or --set is then a user error now, not after the workers have
        # started and imported torch (seconds each); the workers build their own.
        _method(args, names[0])
    rows = map_files(
        _evaluate_file,
        [(path, args, names, progress) for path in clips],
        jobs,
        progress=not args.no_progress,
        desc="evaluate",
        executor=executor,
    )
    docs: dict[str, dict[str, Any]] = {}
    for name in names:  # merged in file order; a method failing on any file: its first error
        errors = [r[name]["error"] for r in rows if "error" in r[name]]
        docs[name] = (
            {"method": name, "preset": args.sensors, "mode": args.mode, "error": errors[0]}
            if errors
            else _doc(args, name, {str(p): r[name] for p, r in zip(clips, rows)})
        )
    lossy = args.gaps or args.faulty > 0
    if len(names) == 1:
        doc = docs[names[0]]
        print(format_table(doc["files"], doc["total"], lossy))
        table_md = format_markdown({**{Path(k).name: v for k, v in doc["files"].items()}, "total": doc["total"]}, lossy)
        out: dict[str, Any] = json_safe_doc(doc)
    else:
        totals = {n: d.get("total", {}) for n, d in docs.items()}
        print(format_table(totals, {}, lossy).rsplit("\n", 1)[0].replace("clip", "method", 1))
        for n, d in docs.items():
            if "error" in d:
                print(f"{n}: not evaluated: {d['error']}")
        table_md = format_markdown(totals, lossy, first="method")
        out = {n: json_safe_doc(d) for n, d in docs.items()}
    if args.markdown:
        write_text(args.markdown, table_md)
        print(f"wrote {args.markdown}")
    if args.json:
        write_text(args.json, json.dumps(out, indent=2) + "\n")
        print(f"wrote {args.json}")
    return 0
