"""``dragposer-studio live --listen PORT``: receive VMC trackers, reconstruct in real time,
and write the result, the recording and the figures (packets, frames solved and
skipped, latency from packet arrival to solved pose)."""

from __future__ import annotations

import argparse
import math
import sys
import time
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from engine.cli.method_options import add_model_options, build_method
from engine.cli.rig_options import add_rig_map_option
from engine.cli.tracker_options import (
    add_tracker_options,
    check_tracker_options,
    default_skeleton,
    load_reference,
    write_json,
)
from engine.errors import UserError
from engine.solver.settings import MODES

if TYPE_CHECKING:
    from engine import skeleton as sk
    from engine.methods.base import Method


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "live",
        help="receive VMC trackers (OSC/UDP) and reconstruct the body in real time",
        description="Listen for VMC packets, solve the newest frame as fast as the method allows, and "
        "write the reconstruction (--out), the raw trackers (--record) and the figures (--json). "
        "See docs/trackers.md.",
    )
    p.add_argument(
        "--listen",
        default="39539",
        metavar="[HOST:]PORT",
        help="UDP port (all interfaces) or HOST:PORT (default: 39539, VMC's)",
    )
    p.add_argument("--record", type=Path, metavar="REC.jsonl", help="record every tracker sample (JSON Lines)")
    p.add_argument(
        "--out", type=Path, metavar="OUT.bvh", help="write the reconstruction: .bvh, .glb or .gltf (docs/export.md)"
    )
    p.add_argument("--duration", type=float, metavar="S", help="stop after S seconds (default: Ctrl-C)")
    p.add_argument("--idle-stop", type=float, metavar="S", help="stop when no frame came for S seconds")
    p.add_argument("--fps", type=float, default=60.0, help="nominal stream rate (default: 60)")
    p.add_argument(
        "--convention",
        choices=("unity", "openxr", "project"),
        default="unity",
        help="axes of the incoming poses (VMC: unity; default: unity)",
    )
    p.add_argument(
        "--timeout",
        type=float,
        default=0.25,
        metavar="S",
        help="a tracker silent for S seconds reads as lost (default: 0.25)",
    )
    add_tracker_options(p)
    add_rig_map_option(p)  # for --reference REF.bvh
    p.add_argument("--method", default="dragposer", help="reconstruction method (default: dragposer)")
    p.add_argument("--mode", choices=MODES, default="realtime", help=argparse.SUPPRESS)
    p.add_argument("--iterations", type=int, metavar="N", help="optimizer iterations per frame")
    p.add_argument(
        "--frame-budget",
        type=float,
        metavar="MS",
        help="milliseconds from a frame's arrival to its solved pose; the solver stops iterating "
        "to meet it (default: 60 %% of the frame period, 10 ms at 60 fps; 0: no budget, all "
        "iterations every frame)",
    )
    p.add_argument("--lr", type=float, metavar="LR", help="Adam learning rate on the latent")
    add_model_options(p)
    p.add_argument("--no-progress", action="store_true", help="hide the status line")
    p.set_defaults(func=_live)


def _check(args: argparse.Namespace) -> None:
    from engine.tracker_io.receiver import parse_listen

    parse_listen(args.listen)
    check_tracker_options(args)
    for name in ("duration", "idle_stop", "timeout", "fps"):
        v = getattr(args, name)
        if v is not None and not (math.isfinite(v) and v > 0):
            raise UserError(f"--{name.replace('_', '-')} must be a positive number of seconds, got {v}")
    if args.frame_budget is not None and not (math.isfinite(args.frame_budget) and args.frame_budget >= 0):
        raise UserError(f"--frame-budget must be a number of milliseconds >= 0, got {args.frame_budget}")
    if args.iterations is not None and not 1 <= args.iterations <= 10000:
        raise UserError(f"--iterations must be in [1, 10000], got {args.iterations}")
    if args.out is not None:
        from engine.motion.formats import motion_format

        motion_format(args.out)  # an unknown extension: before listening, not after the session
    if args.lr is not None and not (math.isfinite(args.lr) and args.lr > 0):
        raise UserError(f"--lr must be > 0, got {args.lr}")


def _live(args: argparse.Namespace) -> int:
    from engine.motion.formats import save_motion
    from engine.tracker_io.live import (
        LiveRun,
        default_budget_ms,
        reference_error,
        to_motion,
    )
    from engine.tracker_io.receiver import VMCReceiver, parse_listen
    from engine.tracker_io.recording import RecordingWriter, header
    from engine.tracker_io.trackers import TrackerMapping

    _check(args)
    host, port = parse_listen(args.listen)
    mapping = TrackerMapping.parse(args.map)
    reference = load_reference(args)
    method = build_method(args)
    _warm_up(method, default_skeleton(reference), args.fps)
    recorder = None
    if args.record:
        recorder = RecordingWriter(
            args.record, header(args.fps, mapping, f"vmc udp {host}:{port}", convention_in=args.convention)
        )
    receiver = VMCReceiver(host, port, mapping, args.convention, args.timeout, recorder)
    budget = default_budget_ms(args.fps) if args.frame_budget is None else args.frame_budget
    run = LiveRun(
        receiver,
        method,
        default_skeleton(reference),
        args.fps,
        args.calibrate,
        args.calibration_pose,
        budget if method.takes_deadline else 0.0,
        keep_frames=args.out is not None or reference is not None,  # else only the figures: an hour stays small
    )
    status = _Status(receiver, disabled=args.no_progress)
    print(f"listening on {receiver.host}:{receiver.port} (method {args.method})", file=sys.stderr, flush=True)
    t0 = time.perf_counter()
    try:
        with receiver:
            result = run.run(args.duration, args.idle_stop, on_frame=status.update)
    except KeyboardInterrupt:
        result = None
    except BaseException:
        if recorder:
            recorder.abort()
        raise
    finally:
        status.close()
    if result is None:  # Ctrl-C: keep what was received, then say so
        print("interrupted", file=sys.stderr)
        result = run.result
    if recorder:
        recorder.close()
    wall = time.perf_counter() - t0
    skeleton = result.calibration.skeleton if result.calibration else default_skeleton(reference)
    rstats = receiver.snapshot_stats()
    stats = {
        **rstats.to_json(),
        "unmapped_trackers": receiver.unmapped_names,
        "frames_received": result.frames_received,
        "frames_solved": result.frames_solved,
        "frames_skipped": result.frames_skipped,
        "frames_skipped_first_solve": result.frames_skipped_first_solve,
        "solved_fraction": result.frames_solved / result.frames_received if result.frames_received else None,
        "calibration_frames": result.calibration_frames,
        "completeness": result.figures.completeness_summary(),
        "latency_ms": result.figures.latency_summary(),
        "ms_per_frame_median": result.figures.solve_median_ms(),
        "frame_budget_ms": run.budget_s * 1000.0 if method.takes_deadline else None,
        "iterations": result.figures.iteration_summary(),
        "tracker_error_cm": result.tracker_error_cm(),
        "reference": reference_error(result.times, result.results, reference),
        "calibration": result.calibration.to_json() if result.calibration else None,
        "skeleton_height_m": skeleton.height(),
        "method": args.method,
        "wall_s": wall,
    }
    if args.out and result.results:
        save_motion(args.out, to_motion(result.times, result.results, skeleton, args.fps, f"live ({args.method})"))
    write_json(args.json, stats)
    print(_report(stats, args, result))
    return 0


def _warm_up(method: Method, skeleton: sk.Skeleton, fps: float) -> None:
    """One untimed solve so the first live frame does not pay for allocations."""
    from engine import skeleton as sk
    from engine.methods import driver
    from engine.sensors import Sensor, SensorFrame

    rest = skeleton.rest_positions()
    readings = {
        j: Sensor(j, rest[sk.JOINT_INDEX[j]] + [0.0, 0.0, 1.0], np.array([1.0, 0.0, 0.0, 0.0]))
        for j in ("upperneck", "lwrist", "rwrist")
    }
    driver.reset(method, skeleton, fps)  # live trackers have no ground truth: such a method stops here
    for k in range(2):
        driver.step(method, SensorFrame(k, readings))


class _Status:
    """A one-line status on stderr: packet rate, frames solved, latency (twice a second)."""

    def __init__(self, receiver, disabled: bool) -> None:
        from tqdm import tqdm

        self.receiver = receiver
        self.bar = tqdm(unit="frame", desc="solved", disable=disabled, leave=False, file=sys.stderr)
        self._last = 0.0
        self._n = 0

    def update(self, result) -> None:
        self.bar.update(result.frames_solved - self._n)
        self._n = result.frames_solved
        now = time.perf_counter()
        if now - self._last >= 0.5:
            self._last = now
            s = self.receiver.snapshot_stats()
            recent = result.figures  # the last two seconds of its newest frames
            lat = sorted(list(recent.latency_ms)[-120:])
            fresh, devices = list(recent.fresh)[-120:], list(recent.devices)[-120:]
            complete = sum(f >= d for f, d in zip(fresh, devices)) / len(fresh)
            self.bar.set_postfix_str(
                f"{s.packet_rate_hz:.0f} pkt/s, skipped {result.frames_skipped}, "
                f"latency p95 {lat[int(0.95 * (len(lat) - 1))]:.1f} ms, "
                f"fresh {fresh[-1]}/{devices[-1]} ({100 * complete:.0f} % complete)"
            )

    def close(self) -> None:
        self.bar.close()


def _report(stats: dict, args: argparse.Namespace, result) -> str:
    lat = stats["latency_ms"]
    frac = stats["solved_fraction"]
    lines = []
    if args.out:
        lines.append(f"wrote {args.out}" if result.results else f"no frame solved: {args.out} not written")
    if args.record:
        lines.append(f"wrote {args.record}")
    if result.calibration:
        lines.append(result.calibration.summary())
    lines.append(
        f"packets {stats['packets']} ({stats['malformed_packets']} malformed, {stats['duplicates']} duplicate, "
        f"{stats['late']} late)  frames {stats['frames_received']} solved {stats['frames_solved']}"
        + (f" ({100 * frac:.1f} %)" if frac is not None else "")
        + f", skipped {stats['frames_skipped']} ({stats['frames_skipped_first_solve']} during the first solve)"
    )
    comp = stats["completeness"]
    if comp["frames"]:
        lines.append(
            f"complete frames {comp['complete']} of {comp['frames']} ({100 * comp['complete_fraction']:.1f} %): "
            f"fresh devices per solved frame mean {comp['fresh_mean']:.2f} of {comp['devices']}, "
            f"min {comp['fresh_min']} ({stats['packet_shape'] or 'shape not known'})"
        )
    if lat["p50"] is not None:
        lines.append(f"latency p50 {lat['p50']:.1f} ms  p95 {lat['p95']:.1f} ms  max {lat['max']:.1f} ms")
    it = stats["iterations"]
    if stats["frame_budget_ms"] and it["median"] is not None:
        lines.append(
            f"frame budget {stats['frame_budget_ms']:.1f} ms: iterations per frame median {it['median']:.0f}, "
            f"mean {it['mean']:.1f}, min {it['min']}"
        )
    te = stats["tracker_error_cm"]
    ref = stats["reference"]
    err = f"{ref['pos_cm']:.2f} cm" if ref.get("pos_cm") is not None else ref["note"]
    lines.append(f"tracker error {te:.2f} cm" if te is not None else "tracker error -")
    lines.append(f"error against the reference: {err}")
    return "\n".join(lines)
