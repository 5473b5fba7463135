"""``dragposer-studio latent CLIP.bvh --sensors P --out report.png [--json F]``: a clip's
reconstruction seen from the latent space (docs/latent.md).

Trackers are simulated from the clip as in ``reconstruct``; DragPoser solves it frame by
frame (progress bar on stderr) and every frame is probed (:mod:`engine.latent`): its place
on the shipped latent map, its distance to the nearest training latent, its norm, the
distance from its prior latent, the flag rule. The PNG shows the map with the clip's
trajectory and the readouts over time (:mod:`engine.latent.report`); ``--json`` writes
the same per frame, with the correlation between the nearest-latent distance and the
frame's position error. A method without a latent (IK, SparsePoser, RPM) is refused
with a message saying so.
"""

from __future__ import annotations

import argparse
from pathlib import Path

from engine.cli.method_options import add_model_options, build_method
from engine.cli.rig_options import add_rig_map_option, asf_path, rig_map_path
from engine.errors import UserError
from engine.solver.settings import MODES


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "latent",
        help="draw a clip's reconstruction on the latent map with per-frame prior readouts (PNG, JSON)",
        description="Simulate trackers from CLIP.bvh, reconstruct it with DragPoser frame by frame and "
        "write a report: the latent map (PCA of the training latents) with the clip's trajectory, the "
        "distance to the nearest training latent, the latent norm, the distance from the prior latent, "
        "and the frames the flag rule marks.",
    )
    p.add_argument("input", type=Path, metavar="CLIP.bvh", help="source motion (any supported rig, or AMC)")
    p.add_argument("--sensors", default="6", help="sensor preset or list, e.g. 6, 4, root,lwrist:3 (default: 6)")
    p.add_argument("--scene", type=Path, metavar="SCENE.json", help="constraints and optimizer settings to add")
    p.add_argument("--out", type=Path, required=True, metavar="REPORT.png", help="the PNG report to write")
    p.add_argument("--json", type=Path, metavar="F.json", help="also write the per-frame readouts as JSON")
    p.add_argument("--method", default="dragposer", help="reconstruction method (only DragPoser has a latent)")
    p.add_argument("--mode", choices=MODES, help="realtime (default) or offline, solved frame by frame")
    p.add_argument("--iterations", type=int, metavar="N", help="iterations per frame (realtime) or the cap (offline)")
    p.add_argument("--lr", type=float, metavar="LR", help="Adam learning rate on the latent")
    p.add_argument("--max-frames", type=int, metavar="N", help="only the first N frames")
    p.add_argument("--faulty", type=float, default=0.0, metavar="P", help="per-frame probability a sensor fails")
    p.add_argument("--gaps", action="store_true", help="simulate hand-tracking gaps")
    p.add_argument("--seed", type=int, default=0, help="seed of the tracker simulation (default: 0)")
    p.add_argument("--no-progress", action="store_true", help="hide the progress bar")
    add_rig_map_option(p)
    add_model_options(p)
    p.set_defaults(func=_latent)


def _latent(args: argparse.Namespace) -> int:
    from engine.validation import check_args, check_input_file, check_output_path

    check_args(args)
    if args.out.suffix.lower() != ".png":
        raise UserError(f"--out {args.out}: the report is a PNG image (name it .png)")
    check_output_path(args.out, "--out")
    if args.json is not None:
        check_output_path(args.json, "--json")
    if args.vae is not None:
        raise UserError(
            "--vae: the shipped latent map belongs to the shipped VAE; build one for yours with "
            "scripts/build_latent_map.py (docs: assets/models/README.md, 'Latent map')"
        )
    check_input_file(args.input)
    from engine.latent.probe import NO_LATENT, LatentProbe, SolvesInLatent
    from engine.latent.report import render_report, write_json
    from engine.latent.trace import trace_clip
    from engine.motion.retarget import manifest_fps, retarget, source_frames_needed
    from engine.motion.source_file import load_source
    from engine.tracking import parse_sensors, simulate

    parse_sensors(args.sensors)  # fail before loading anything
    method = build_method(args)
    if not isinstance(method, SolvesInLatent):
        raise UserError(NO_LATENT.format(method=args.method))
    probe = LatentProbe.shipped()
    raw = load_source(args.input, source_frames_needed(args.max_frames), asf_path(args))
    motion, _ = retarget(raw, manifest_fps(args.input), rig_map=rig_map_path(args))
    if args.max_frames:
        motion = motion.slice(0, args.max_frames)
    if len(motion) == 0:
        raise UserError(f"{args.input}: the clip has no frames")
    tracking = simulate(motion, args.sensors, faulty=args.faulty, gaps=args.gaps, seed=args.seed)
    trace = trace_clip(method, tracking, motion, probe, progress=not args.no_progress)
    render_report(trace, probe.map, args.out, args.method)
    if args.json is not None:
        write_json(trace, probe.map, args.json, args.method)
    s = trace.summary()
    corr = s.get("correlation_nearest_pos", {})
    print(f"wrote {args.out}" + (f" and {args.json}" if args.json else ""))
    print(
        f"frames {s['frames']}  flagged {len(s['flagged'])}  nearest p50 {s['nearest'].get('p50', float('nan')):.3f} "
        f"max {s['nearest'].get('max', float('nan')):.3f}  Pos {s.get('pos_cm', float('nan')):.2f} cm  "
        f"r(nearest, Pos) {corr.get('pearson', float('nan')):.2f}"
    )
    return 0
