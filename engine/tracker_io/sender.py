"""Stream a clip's simulated trackers as VMC packets in real time (tests and demos).

Trackers are simulated from the clip (:func:`engine.tracking.simulate`: the same
presets, the same Gaussian position noise), optionally preceded by a still T-pose for
calibration and offset as real devices would be (:data:`HARDWARE_OFFSETS`). By default
every frame is one OSC bundle (:func:`engine.tracker_io.vmc.encode_frame`) whose
``/VMC/Ext/T`` is the clip time, so a receiver can line frames up with the clip
(``--reference``); the other shapes senders use (one message per datagram, the time
first, last or not at all, :data:`engine.tracker_io.vmc.SHAPES`) are sent back to back at
the frame's time. Frames are sent on a fixed schedule (``start + i / fps``, no drift); a
dropped datagram is simply not sent.
"""

from __future__ import annotations

import socket
import time
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from engine import skeleton as sk
from engine.errors import UserError
from engine.kinematics import quaternion as Q
from engine.motion.clip import Motion
from engine.tracker_io.calibration import standing_root_height
from engine.tracker_io.trackers import DEFAULT_SLOTS
from engine.tracker_io.vmc import SHAPES, encode_packets

#: Tracker name the sender uses for each joint (the default mapping, inverted).
TRACKER_NAMES: dict[str, str] = {j: n for n, j in DEFAULT_SLOTS.items()}


def _about(axis: tuple[float, float, float], deg: float) -> np.ndarray:
    return Q.from_axis_angle(np.array(axis, float), np.radians(deg))


#: Typical mounting of real devices, joint -> (offset in the joint's frame, metres;
#: rotation of the device relative to the joint). In the rest pose the joint frames are
#: the world's: -Y forward, +Z up, +X the wearer's left. A headset sits 9 cm in front of
#: the head joint, a controller grip in the palm, ankle pucks on the instep, the hip puck
#: on the belt at the back, turned round.
HARDWARE_OFFSETS: dict[str, tuple[np.ndarray, np.ndarray]] = {
    "upperneck": (np.array([0.0, -0.09, 0.0]), _about((1, 0, 0), 10.0)),
    "lwrist": (np.array([0.0, -0.04, -0.03]), _about((1, 0, 0), -40.0)),
    "rwrist": (np.array([0.0, -0.04, -0.03]), _about((1, 0, 0), -40.0)),
    "root": (np.array([0.0, 0.08, 0.02]), _about((0, 0, 1), 180.0)),
    "lankle": (np.array([0.0, -0.05, 0.04]), _about((1, 0, 0), 20.0)),
    "rankle": (np.array([0.0, -0.05, 0.04]), _about((1, 0, 0), 20.0)),
}


def with_tpose(motion: Motion, seconds: float) -> Motion:
    """``motion`` preceded by ``seconds`` of the still rest T-pose, standing on the floor
    where the clip starts, facing its first heading."""
    n = int(round(seconds * motion.fps))
    if n <= 0:
        return motion
    local = np.tile(Q.identity((sk.NUM_JOINTS,)), (n, 1, 1))
    local[:, 0] = Q.heading(motion.local_rot[0, 0])
    root = np.tile(motion.root_pos[0], (n, 1))
    root[:, 2] = standing_root_height(motion.skeleton)
    return Motion(
        np.concatenate([local, motion.local_rot]),
        np.concatenate([root, motion.root_pos]),
        motion.skeleton,
        motion.fps,
        motion.name,
    )


@dataclass
class StreamPlan:
    """What the sender will send: per frame, a time and every tracker's pose.

    Attributes
    ----------
    times : ndarray (F,)
        ``/VMC/Ext/T`` of each frame, seconds (0 = the clip's first frame; a calibration
        T-pose has negative times).
    names : tuple of str
        Tracker names.
    positions : ndarray (F, S, 3)
    rotations : ndarray (F, S, 4)
        Project frame.
    """

    times: np.ndarray
    names: tuple[str, ...]
    positions: np.ndarray
    rotations: np.ndarray

    def __len__(self) -> int:
        return len(self.times)

    def frame(self, i: int) -> list[tuple[str, np.ndarray, np.ndarray]]:
        return [(n, self.positions[i, k], self.rotations[i, k]) for k, n in enumerate(self.names)]


def scaled_motion(motion: Motion, factor: float) -> Motion:
    """The same motion by a subject ``factor`` times the size (bones and root path)."""
    if factor == 1.0:
        return motion
    return Motion(
        motion.local_rot,
        motion.root_pos * factor,
        sk.Skeleton(motion.skeleton.offsets * factor),
        motion.fps,
        motion.name,
    )


def plan_stream(
    motion: Motion,
    sensors: str = "6",
    noise_pos_m: float = 0.0,
    seed: int = 0,
    tpose_s: float = 0.0,
    hardware_offsets: bool = False,
    fps: float | None = None,
) -> StreamPlan:
    """Simulate the trackers of ``motion`` for sending (see module docs).

    ``fps`` (default: the clip's) is the sending rate; frames are then picked nearest in
    time from the clip.
    """
    from engine.tracking import simulate

    lead = int(round(tpose_s * motion.fps)) if tpose_s > 0 else 0
    full = with_tpose(motion, tpose_s)
    tr = simulate(full, sensors, noise_pos_m=noise_pos_m, seed=seed)
    pos, rot = tr.positions.copy(), tr.rotations.copy()
    if hardware_offsets:
        for k, j in enumerate(tr.joints):
            if j in HARDWARE_OFFSETS and tr.dof[k] == 6:
                d, r = HARDWARE_OFFSETS[j]
                pos[:, k] = pos[:, k] + Q.rotate(rot[:, k], np.broadcast_to(d, pos[:, k].shape))
                rot[:, k] = Q.normalize(Q.mul(rot[:, k], np.broadcast_to(r, rot[:, k].shape)))
    names = tuple(TRACKER_NAMES.get(j, j) for j in tr.joints)
    times = (np.arange(len(full)) - lead) / full.fps
    if fps is not None and fps != full.fps:
        n = int(np.floor((len(full) - 1) / full.fps * fps)) + 1
        pick = np.minimum(np.round(np.arange(n) * full.fps / fps).astype(int), len(full) - 1)
        times = np.arange(n) / fps - lead / full.fps
        pos, rot = pos[pick], rot[pick]
    return StreamPlan(times, names, pos, rot)


@dataclass
class SendStats:
    """What :func:`send_stream` sent: frames, those sent whole (``sent``) and those with a
    datagram dropped (``dropped``), and datagrams."""

    frames: int = 0
    sent: int = 0
    dropped: int = 0
    late_ms_max: float = 0.0
    packets: int = 0
    packets_dropped: int = 0


def parse_target(text: str) -> tuple[str, int]:
    """``HOST:PORT`` -> (host, port)."""
    host, sep, port = str(text).rpartition(":")
    try:
        p = int(port)
    except ValueError:
        p = -1
    if not sep or not host or not 1 <= p <= 65535:
        raise UserError(f"--to {text!r}: expected HOST:PORT with a port in [1, 65535]")
    return host, p


def send_stream(
    plan: StreamPlan,
    host: str,
    port: int,
    fps: float,
    drop: float = 0.0,
    seed: int = 0,
    convention: str = "unity",
    realtime: bool = True,
    on_frame: Callable[[int], None] | None = None,
    shape: str = "bundle",
    chatter: bool = False,
) -> SendStats:
    """Send the plan to ``host:port``, one frame at ``fps``.

    Parameters
    ----------
    drop : float
        Probability that a datagram is not sent (simulated network loss): the frame's
        bundle, or one of its messages.
    realtime : bool
        Keep the schedule ``start + i / fps``; False sends as fast as possible.
    on_frame : callable, optional
        Called with the frame index after each frame (progress bars).
    shape : str
        How a frame goes on the wire (:data:`engine.tracker_io.vmc.SHAPES`).
    chatter : bool
        Also send ``/VMC/Ext/OK``, root and bone messages, as a VMC performer does.
    """
    if not 0.0 <= drop <= 1.0:
        raise UserError(f"--drop must be a probability in [0, 1], got {drop}")
    if shape not in SHAPES:
        raise UserError(f"--packets must be one of {', '.join(SHAPES)}, got {shape!r}")
    rng = np.random.default_rng(seed + 1)
    stats = SendStats()
    sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    try:
        start = time.perf_counter()
        for i in range(len(plan)):
            if realtime:
                due = start + i / fps
                wait = due - time.perf_counter()
                if wait > 0:
                    time.sleep(wait)
                else:
                    stats.late_ms_max = max(stats.late_ms_max, -1000.0 * wait)
            stats.frames += 1
            lost = 0
            for dgram in encode_packets(float(plan.times[i]), plan.frame(i), convention, shape, chatter):
                if drop and rng.random() < drop:
                    lost += 1
                    continue
                try:
                    sock.sendto(dgram, (host, port))
                except OSError as exc:
                    raise UserError(f"cannot send to {host}:{port} ({exc.strerror})") from None
                stats.packets += 1
            stats.packets_dropped += lost
            stats.dropped += bool(lost)
            stats.sent += not lost
            if on_frame is not None:
                on_frame(i)
    finally:
        sock.close()
    return stats
