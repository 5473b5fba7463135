"""``dragposer-studio send CLIP.bvh --to HOST:PORT``: stream a clip's simulated trackers
as VMC (OSC over UDP) in real time, for testing the live path and for demos."""

from __future__ import annotations

import argparse
import math
from pathlib import Path

from engine.cli.rig_options import add_rig_map_option, asf_path, rig_map_path
from engine.errors import UserError
from engine.tracker_io.vmc import SHAPES


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "send",
        help="stream a clip's simulated trackers as VMC packets (OSC/UDP) in real time",
        description="Simulate trackers from CLIP.bvh and send them to HOST:PORT, by default one VMC bundle per "
        "frame (/VMC/Ext/T = clip time, then /VMC/Ext/Hmd|Con|Tra/Pos per tracker, Unity axes); --packets sends "
        "one message per datagram instead. See docs/trackers.md.",
    )
    p.add_argument("input", type=Path, metavar="CLIP.bvh", help="motion to stream (any supported rig)")
    p.add_argument("--to", required=True, metavar="HOST:PORT", help="receiver address, e.g. 127.0.0.1:39539")
    p.add_argument("--sensors", default="6", help="sensor preset or list (default: 6)")
    p.add_argument("--fps", type=float, default=60.0, help="frames per second to send (default: 60)")
    p.add_argument("--noise-pos", type=float, default=0.0, metavar="M", help="Gaussian position noise, metres")
    p.add_argument(
        "--drop",
        type=float,
        default=0.0,
        metavar="P",
        help="probability that a datagram (a frame's bundle, or one message) is lost",
    )
    p.add_argument(
        "--packets",
        choices=SHAPES,
        default="bundle",
        help="bundle: one OSC bundle per frame (default); time-first / time-last: one message per "
        "datagram, /VMC/Ext/T before / after the devices; no-time: one message per datagram, "
        "no /VMC/Ext/T",
    )
    p.add_argument(
        "--chatter",
        action="store_true",
        help="also send /VMC/Ext/OK, /VMC/Ext/Root/Pos and /VMC/Ext/Bone/Pos, as a VMC performer does",
    )
    p.add_argument(
        "--tpose",
        type=float,
        default=0.0,
        metavar="SECONDS",
        help="stand still in a T-pose for SECONDS before the clip (for --calibrate)",
    )
    p.add_argument("--scale", type=float, default=1.0, metavar="F", help="scale the subject by F (e.g. 1.1)")
    p.add_argument(
        "--hardware-offsets",
        action="store_true",
        help="mount the trackers as real devices sit (headset in front of the head, ...)",
    )
    p.add_argument("--max-frames", type=int, metavar="N", help="send only the first N clip frames")
    p.add_argument(
        "--convention",
        choices=("unity", "openxr", "project"),
        default="unity",
        help="axes to send in (VMC is unity; default: unity)",
    )
    p.add_argument("--seed", type=int, default=0, help="seed of noise and drops (default: 0)")
    p.add_argument("--no-progress", action="store_true", help="hide the progress bar")
    add_rig_map_option(p)
    p.set_defaults(func=_send)


def _check(args: argparse.Namespace) -> None:
    from engine.tracker_io.sender import parse_target
    from engine.tracking import parse_sensors

    parse_target(args.to)
    parse_sensors(args.sensors)
    checks = [
        ("--fps", args.fps, 1.0, 1000.0),
        ("--noise-pos", args.noise_pos, 0.0, 1.0),
        ("--drop", args.drop, 0.0, 1.0),
        ("--tpose", args.tpose, 0.0, 60.0),
        ("--scale", args.scale, 0.5, 2.0),
    ]
    for name, v, lo, hi in checks:
        if not (math.isfinite(v) and lo <= v <= hi):
            raise UserError(f"{name} must be in [{lo:g}, {hi:g}], got {v}")
    if args.max_frames is not None and args.max_frames < 1:
        raise UserError(f"--max-frames must be at least 1, got {args.max_frames}")
    if not 0 <= args.seed < 2**32:
        raise UserError(f"--seed must be in [0, 2^32), got {args.seed}")


def _send(args: argparse.Namespace) -> int:
    import sys

    from tqdm import tqdm

    from engine.motion.retarget import load_motion
    from engine.tracker_io.sender import parse_target, plan_stream, scaled_motion, send_stream

    _check(args)
    host, port = parse_target(args.to)
    motion = load_motion(args.input, rig_map=rig_map_path(args), asf=asf_path(args))
    if args.max_frames:
        motion = motion.slice(0, args.max_frames)
    motion = scaled_motion(motion, args.scale)
    plan = plan_stream(motion, args.sensors, args.noise_pos, args.seed, args.tpose, args.hardware_offsets, args.fps)
    print(
        f"sending {len(plan)} frames ({len(plan) / args.fps:.1f} s) of {', '.join(plan.names)} to {host}:{port}; "
        f"subject height {motion.skeleton.height():.3f} m",
        file=sys.stderr,
        flush=True,
    )
    with tqdm(total=len(plan), unit="frame", disable=args.no_progress, leave=False) as bar:
        stats = send_stream(
            plan,
            host,
            port,
            args.fps,
            args.drop,
            args.seed,
            args.convention,
            on_frame=lambda i: bar.update(1),
            shape=args.packets,
            chatter=args.chatter,
        )
    print(
        f"sent {stats.sent} of {stats.frames} frames whole ({stats.dropped} lost a datagram) in {stats.packets} "
        f"datagrams ({args.packets}, {stats.packets_dropped} dropped); "
        f"sender late by up to {stats.late_ms_max:.1f} ms"
    )
    return 0
