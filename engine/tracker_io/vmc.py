"""The VMC protocol (Virtual Motion Capture, OSC over UDP): the messages we read and
write, encoded and decoded with python-osc.

Messages (all positions in Unity's left-handed, Y-up world, metres; quaternions
``(x, y, z, w)``; :mod:`engine.tracker_io.coords` converts):

==================== ================================================ ======================
address              arguments                                        what
==================== ================================================ ======================
``/VMC/Ext/Hmd/Pos`` ``s name, f px, py, pz, f qx, qy, qz, qw``       headset
``/VMC/Ext/Con/Pos`` same                                             controllers
``/VMC/Ext/Tra/Pos`` same                                             trackers (pucks)
``/VMC/Ext/T``       ``f time`` (seconds)                             stream time of the frame
==================== ================================================ ======================

The ``/Local`` variants of the three pose addresses are read the same way. Other VMC
messages (bones, blend shapes, ``/VMC/Ext/OK``...) are counted and ignored. Our sender
sends one OSC bundle per frame: ``/VMC/Ext/T`` with the clip time, then one pose message
per tracker.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from pythonosc.osc_bundle_builder import IMMEDIATELY, OscBundleBuilder
from pythonosc.osc_message_builder import OscMessageBuilder
from pythonosc.osc_packet import OscPacket, ParseError

from engine.tracker_io.coords import from_project, to_project, wxyz_to_xyzw, xyzw_to_wxyz

TIME = "/VMC/Ext/T"
HMD = "/VMC/Ext/Hmd/Pos"
CONTROLLER = "/VMC/Ext/Con/Pos"
TRACKER = "/VMC/Ext/Tra/Pos"
POSE_ADDRESSES = frozenset({HMD, CONTROLLER, TRACKER, HMD + "/Local", CONTROLLER + "/Local", TRACKER + "/Local"})

#: Address our sender uses per tracker name (others go out as ``/VMC/Ext/Tra/Pos``).
SEND_ADDRESS = {"head": HMD, "left_hand": CONTROLLER, "right_hand": CONTROLLER}

__all__ = ["ParseError", "Pose", "Packet", "decode_packet", "encode_frame"]


@dataclass(frozen=True)
class Pose:
    """One decoded tracker pose, project frame (metres; quaternion w, x, y, z)."""

    tracker: str
    position: np.ndarray
    rotation: np.ndarray


@dataclass
class Packet:
    """What one datagram held.

    Attributes
    ----------
    time : float or None
        The ``/VMC/Ext/T`` value, seconds, if the packet had one.
    poses : list of Pose
    malformed : int
        Pose messages with wrong arguments (count, type, non-finite, zero quaternion).
    other : int
        Messages at addresses we do not read.
    """

    time: float | None
    poses: list[Pose]
    malformed: int = 0
    other: int = 0


def encode_frame(t: float, poses: Sequence[tuple[str, np.ndarray, np.ndarray]], convention: str = "unity") -> bytes:
    """One OSC bundle with the frame's time and every tracker's pose.

    Parameters
    ----------
    t : float
        Stream time, seconds (sent as ``/VMC/Ext/T``).
    poses : sequence of (name, position (3,), rotation (4,) w, x, y, z)
        Project frame.
    convention : str
        Axes to send in (VMC is ``unity``).
    """
    bundle = OscBundleBuilder(IMMEDIATELY)
    msg = OscMessageBuilder(TIME)
    msg.add_arg(float(t), "f")
    bundle.add_content(msg.build())
    for name, pos, rot in poses:
        p, q = from_project(pos, rot, convention)
        m = OscMessageBuilder(SEND_ADDRESS.get(name, TRACKER))
        m.add_arg(name, "s")
        for v in (*p, *wxyz_to_xyzw(q)):
            m.add_arg(float(v), "f")
        bundle.add_content(m.build())
    return bundle.build().dgram


def decode_packet(dgram: bytes, convention: str = "unity") -> Packet:
    """Decode one datagram.

    Raises
    ------
    ParseError
        When the datagram is not OSC at all (the caller counts it as malformed).
    """
    packet = OscPacket(dgram)
    out = Packet(None, [])
    for timed in packet.messages:
        msg = timed.message
        addr, args = msg.address, msg.params
        if addr == TIME:
            if len(args) >= 1 and _is_number(args[0]) and math.isfinite(args[0]):
                out.time = float(args[0])
            else:
                out.malformed += 1
        elif addr in POSE_ADDRESSES:
            pose = _pose(args, convention)
            if pose is None:
                out.malformed += 1
            else:
                out.poses.append(pose)
        else:
            out.other += 1
    return out


def _is_number(v: object) -> bool:
    return isinstance(v, (int, float)) and not isinstance(v, bool)


def _pose(args: list, convention: str) -> Pose | None:
    if len(args) < 8 or not isinstance(args[0], str) or not args[0]:
        return None
    vals = args[1:8]
    if not all(_is_number(v) for v in vals):
        return None
    a = np.array(vals, float)
    if not np.all(np.isfinite(a)):
        return None
    q = xyzw_to_wxyz(a[3:])
    n = float(np.linalg.norm(q))
    if n < 1e-6:
        return None
    pos, rot = to_project(a[:3], q / n, convention)
    return Pose(args[0], pos, rot)
