"""``dragposer-studio reconstruct --trackers REC.jsonl --out OUT.bvh``: reconstruct a
tracker recording offline, every frame, with the same readings the live run had."""

from __future__ import annotations

import argparse
from typing import Any

import numpy as np

from engine.cli.tracker_options import check_tracker_options, default_skeleton, load_reference, write_json


def _slice(tracking: Any, start: int, stop: int | None = None) -> Any:
    from engine.tracking import Tracking

    sl = slice(start, stop)
    return Tracking(
        tracking.joints,
        tracking.dof,
        tracking.positions[sl],
        tracking.rotations[sl],
        tracking.connected[sl],
        tracking.fps,
    )


def reconstruct_trackers(args: argparse.Namespace) -> int:
    from engine.cli.export_options import export_contents
    from engine.cli.method_options import build_method
    from engine.methods import run_method
    from engine.motion.formats import save_motion
    from engine.tracker_io.calibration import calibrate
    from engine.tracker_io.live import calibration_window, reference_error, to_motion, tracker_error_cm
    from engine.tracker_io.recording import read_recording, replay
    from engine.tracker_io.trackers import TrackerMapping

    check_tracker_options(args)
    rec = read_recording(args.trackers)
    mapping = TrackerMapping.parse(args.map) if args.map else rec.mapping
    reference = load_reference(args)
    tracking, times = replay(rec.samples, mapping, fps=rec.fps)
    skeleton = default_skeleton(reference)
    cal = None
    start = 0
    if args.calibrate > 0:
        start = calibration_window(times, args.calibrate)
        cal = calibrate([tracking.frame(i) for i in range(start)], args.calibration_pose)
        tracking, times = replay(rec.samples, mapping, cal, fps=rec.fps)
        skeleton = cal.skeleton
    stop = start + args.max_frames if args.max_frames else None
    tracking, times = _slice(tracking, start, stop), times[start:stop]
    method = build_method(args)
    if len(tracking) == 0:
        from engine.errors import UserError

        raise UserError(f"{args.trackers}: no frame left to reconstruct after the calibration window")
    _, results = run_method(method, tracking, skeleton, progress=not args.no_progress, desc=args.trackers.name)
    motion = to_motion(times, results, skeleton, tracking.fps, f"{args.trackers.stem} ({args.method})")
    save_motion(args.out, motion, contents=export_contents(args))
    frames = [tracking.frame(i) for i in range(len(tracking))]
    stats = {
        "frames_solved": len(results),
        "calibration_frames": start,
        "ms_per_frame_median": float(np.median([r.ms for r in results])),
        "tracker_error_cm": tracker_error_cm(results, frames),
        "reference": reference_error(times, results, reference),
        "calibration": cal.to_json() if cal else None,
        "skeleton_height_m": skeleton.height(),
        "method": args.method,
    }
    write_json(args.json, stats)
    ref = stats["reference"]
    lines = [f"wrote {args.out}"]
    if cal:
        lines.append(cal.summary())
    te = stats["tracker_error_cm"]
    lines.append(
        f"frames {len(results)}  ms/frame median {stats['ms_per_frame_median']:.1f}  "
        f"tracker error {'-' if te is None else f'{te:.2f} cm'}"
    )
    lines.append(
        "error against the reference: " + (f"{ref['pos_cm']:.2f} cm" if ref.get("pos_cm") is not None else ref["note"])
    )
    print("\n".join(lines))
    return 0
