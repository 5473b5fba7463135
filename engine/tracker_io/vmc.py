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
sends one OSC bundle per frame by default: ``/VMC/Ext/T`` with the clip time, then one
pose message per tracker; it can also send one message per datagram in the other shapes
senders use (:data:`SHAPES`; :mod:`engine.tracker_io.framing` reads them all).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from pythonosc.osc_bundle_builder import IMMEDIATELY, OscBundleBuilder
from pythonosc.osc_message import OscMessage
from pythonosc.osc_message_builder import OscMessageBuilder
from pythonosc.osc_packet import OscPacket, ParseError

from engine.tracker_io.coords import from_project, to_project, wxyz_to_xyzw, xyzw_to_wxyz

TIME = "/VMC/Ext/T"
HMD = "/VMC/Ext/Hmd/Pos"
CONTROLLER = "/VMC/Ext/Con/Pos"
TRACKER = "/VMC/Ext/Tra/Pos"
OK = "/VMC/Ext/OK"
ROOT = "/VMC/Ext/Root/Pos"
BONE = "/VMC/Ext/Bone/Pos"
POSE_ADDRESSES = frozenset({HMD, CONTROLLER, TRACKER, HMD + "/Local", CONTROLLER + "/Local", TRACKER + "/Local"})

#: Address our sender uses per tracker name (others go out as ``/VMC/Ext/Tra/Pos``).
SEND_ADDRESS = {"head": HMD, "left_hand": CONTROLLER, "right_hand": CONTROLLER}
#: Humanoid bone our sender names in ``/VMC/Ext/Bone/Pos`` chatter, per tracker name.
CHATTER_BONE = {
    "head": "Head",
    "left_hand": "LeftHand",
    "right_hand": "RightHand",
    "hips": "Hips",
    "left_foot": "LeftFoot",
    "right_foot": "RightFoot",
}

#: How a frame goes on the wire: one bundle, or one message per datagram with the time
#: before the devices, after them, or not at all.
SHAPES = ("bundle", "time-first", "time-last", "no-time")

__all__ = ["ParseError", "Pose", "Packet", "SHAPES", "decode_packet", "encode_frame", "encode_packets"]


@dataclass(frozen=True)
class Pose:
    """One decoded tracker pose, project frame (metres; quaternion w, x, y, z), and the
    address it came on (a sender may send a device on ``/Pos`` and ``/Pos/Local``)."""

    tracker: str
    position: np.ndarray
    rotation: np.ndarray
    address: str = ""


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


def encode_frame(
    t: float, poses: Sequence[tuple[str, np.ndarray, np.ndarray]], convention: str = "unity", chatter: bool = False
) -> bytes:
    """One OSC bundle with the frame's time and every tracker's pose.

    Parameters
    ----------
    t : float
        Stream time, seconds (sent as ``/VMC/Ext/T``).
    poses : sequence of (name, position (3,), rotation (4,) w, x, y, z)
        Project frame.
    convention : str
        Axes to send in (VMC is ``unity``).
    chatter : bool
        Also the messages a VMC performer sends besides the devices (:func:`encode_packets`).
    """
    bundle = OscBundleBuilder(IMMEDIATELY)
    for m in _messages(t, poses, convention, "time-first", chatter):
        bundle.add_content(m)
    return bundle.build().dgram


def encode_packets(
    t: float,
    poses: Sequence[tuple[str, np.ndarray, np.ndarray]],
    convention: str = "unity",
    shape: str = "bundle",
    chatter: bool = False,
) -> list[bytes]:
    """The datagrams of one frame in ``shape`` (:data:`SHAPES`): one bundle
    (:func:`encode_frame`), or one message per datagram with ``/VMC/Ext/T`` first, last or
    left out. ``chatter`` adds ``/VMC/Ext/OK``, ``/VMC/Ext/Root/Pos`` and one
    ``/VMC/Ext/Bone/Pos`` per device (a bone message has a device message's arguments),
    mixed in among the devices."""
    if shape not in SHAPES:
        raise ValueError(f"unknown packet shape {shape!r}; known: {', '.join(SHAPES)}")
    if shape == "bundle":
        return [encode_frame(t, poses, convention, chatter)]
    return [m.dgram for m in _messages(t, poses, convention, shape, chatter)]


def _messages(
    t: float, poses: Sequence[tuple[str, np.ndarray, np.ndarray]], convention: str, shape: str, chatter: bool
) -> list[OscMessage]:
    time_msg = OscMessageBuilder(TIME)
    time_msg.add_arg(float(t), "f")
    out = [time_msg.build()] if shape == "time-first" else []
    if chatter:
        ok = OscMessageBuilder(OK)
        ok.add_arg(1, "i")
        out += [ok.build(), _pose_message(ROOT, "root", np.zeros(3), np.array([1.0, 0.0, 0.0, 0.0]), convention)]
    for name, pos, rot in poses:
        out.append(_pose_message(SEND_ADDRESS.get(name, TRACKER), name, pos, rot, convention))
        if chatter:
            out.append(_pose_message(BONE, CHATTER_BONE.get(name, name), pos, rot, convention))
    if shape == "time-last":
        out.append(time_msg.build())
    return out


def _pose_message(address: str, name: str, pos: np.ndarray, rot: np.ndarray, convention: str) -> OscMessage:
    p, q = from_project(pos, rot, convention)
    m = OscMessageBuilder(address)
    m.add_arg(name, "s")
    for v in (*p, *wxyz_to_xyzw(q)):
        m.add_arg(float(v), "f")
    return m.build()


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
            pose = _pose(addr, args, convention)
            if pose is None:
                out.malformed += 1
            else:
                out.poses.append(pose)
        else:
            out.other += 1
    return out


def _is_number(v: object) -> bool:
    return isinstance(v, (int, float)) and not isinstance(v, bool)


def _pose(address: str, args: list, convention: str) -> Pose | None:
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
    return Pose(args[0], pos, rot, address)
