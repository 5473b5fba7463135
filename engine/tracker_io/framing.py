"""Frames from the structure of a VMC stream: which datagrams make up one frame, and its time.

VMC senders put a frame on the wire in one of these shapes (``docs/trackers.md`` shows
each); the assembler tells them apart by themselves, per stream:

* **bundle**: one datagram holds ``/VMC/Ext/T`` and the devices (``send``'s default). It
  is a frame of its own, complete on arrival.
* **time first**: ``/VMC/Ext/T`` alone, then one datagram per device. A datagram without a
  time belongs to the frame of the latest time. The frame closes as soon as every
  *expected* device has arrived, else when the next time arrives.
* **time last**: one datagram per device, then ``/VMC/Ext/T``. The devices wait for the time,
  which closes their frame.
* **no time**: one datagram per device and never a time. A frame is a burst of devices:
  it closes as soon as every expected device has arrived, when a device repeats, or after
  a silence of half the stream's frame period (the median over the last frames; at least
  :data:`FRAME_GAP_S`). Its time is the arrival of its first datagram.

Whether a lone time starts or ends its frame cannot be told from the order of the
datagrams (``T D D D T D D D`` reads both ways), only from their timing: a frame's
datagrams come in a burst and frames a period apart, so a time that starts its frame
follows a longer silence than the one after it, and a time that ends it the other way
round. Every lone time votes so at the next datagram; three agreeing votes in a row set
the order, seven of the last eight against it turn it over (one arrival stamped late by a
receiver thread waiting for the interpreter does not). Until the order is set, each time
is placed by its own vote, once the next datagram has arrived.

A stream is taken as one without time when a device repeats before any time was seen;
devices are held until then. In a stream with time, devices whose time never comes (its
datagram was lost, so a device repeats under the latest time or while they wait) are
dropped and counted as :attr:`FrameAssembler.untimed`. Only a stream without time has a silence rule: a sender
that stalls in the middle of a frame (a busy machine) then splits it in two, where a
time keeps it whole.

*Expected* devices are those in each of the last two frames: a device that stops sending
is no longer waited for after two frames, one that sends every other frame never is.
Chatter (``/VMC/Ext/OK``, root, bones...) carries no device; it counts as a datagram for
the votes only.

The rules read the *wire* time of each datagram: when the kernel received it, where the
receiver can get that (``SO_TIMESTAMPNS`` on Linux). The receiver thread's own stamp waits
for the interpreter, up to several milliseconds for each datagram while the solver runs
Python, which could spread a burst's datagrams over the silences that separate frames.
The receiver's stamp stays the frame's ``arrival`` (latency is measured from it, as for a
bundle).
"""

from __future__ import annotations

import math
from collections import deque
from dataclasses import dataclass, field

import numpy as np

from engine.tracker_io.vmc import Packet, Pose

#: Seconds of silence that close a frame of a sender without time, at least (module doc):
#: a burst's datagrams come well within it, frames at up to 120 Hz further apart.
FRAME_GAP_S = 0.004
#: Frame starts over which a sender without time has its frame period measured.
PERIOD_FRAMES = 16

#: Votes in a row that set the order of a stream's lone times; of the last eight, the
#: votes against it that turn it over.
VOTES_TO_SET, VOTES_TO_TURN, VOTE_WINDOW = 3, 7, 8


@dataclass
class Piece:
    """What the receiver applies: device poses at stream time ``t``.

    Attributes
    ----------
    t : float
        Stream time of the frame the poses belong to, seconds.
    poses : list of Pose
        May be empty (a piece that only closes its frame).
    arrival : float
        The receiver's stamp of the frame's newest datagram so far (``time.perf_counter()``).
    close : bool
        The frame at ``t`` is complete: publish it (again, with a straggler's pose, if it
        was published already).
    """

    t: float
    poses: list[Pose]
    arrival: float
    close: bool


@dataclass
class _Open:
    """The frame being assembled; ``t`` None while its devices wait for a time."""

    t: float | None
    first_wire: float
    last_wire: float
    last_arrival: float
    names: set[tuple[str, str]] = field(default_factory=set)  # devices in it: (name, address)
    waiting: list[Pose] = field(default_factory=list)
    closed: bool = False
    bundle: bool = False


class FrameAssembler:
    """Turn decoded datagrams into :class:`Piece` s (module doc).

    Parameters
    ----------
    gap_s : float
        Least silence that closes a frame of a sender without time, seconds.
    clock_origin : float
        Wire time that is stream time 0 for a sender without time.
    """

    def __init__(self, gap_s: float = FRAME_GAP_S, clock_origin: float = 0.0) -> None:
        self.gap_s = float(gap_s)
        self.clock_origin = float(clock_origin)
        #: ``"first"`` or ``"last"``: where a lone time sits in its frame; None until set.
        self.order: str | None = None
        #: True once a time was seen, False once a device repeated before any; None before.
        self.timed: bool | None = None
        #: Device poses dropped because their frame's time never came.
        self.untimed = 0
        self._votes: deque[str] = deque(maxlen=VOTE_WINDOW)
        self._last: float | None = None  # wire time of the previous datagram
        self._vote_gap: float | None = None  # silence before the newest lone time, until it votes
        self._pending: tuple[float, float, float] | None = None  # a lone time (t, arrival, wire) waiting for its vote
        self._frame: _Open | None = None
        self._recent: deque[frozenset[tuple[str, str]]] = deque(maxlen=2)
        self._starts: deque[float] = deque(maxlen=PERIOD_FRAMES + 1)  # wire times of untimed frames' starts

    @property
    def shape(self) -> str:
        """The stream's packet shape as seen so far: ``bundle``, ``time-first``,
        ``time-last``, ``no-time`` or ``""`` (not known yet)."""
        if self._frame is not None and self._frame.bundle:
            return "bundle"
        if self.timed is False:
            return "no-time"
        return f"time-{self.order}" if self.timed and self.order else ""

    def deadline(self) -> float | None:
        """Wire time when :meth:`expire` may next have something to do."""
        times = []
        if self._pending is not None and self._last is not None:
            times.append(self._last + max(self.gap_s, self._vote_gap or 0.0))
        f = self._frame
        if self.timed is False and f is not None and not f.closed:
            times.append(f.last_wire + self.silence())
        return min(times) if times else None

    def silence(self) -> float:
        """The silence that closes a frame of a sender without time: half its frame period."""
        if len(self._starts) < 3:
            return self.gap_s
        return max(self.gap_s, 0.5 * float(np.median(np.diff(self._starts))))

    def expire(self, now: float) -> list[Piece]:
        """Apply the silence rules at wire time ``now``: a lone time followed by a longer silence
        than the one before it ends its frame; a frame of a sender without time closes after
        :meth:`silence`."""
        out: list[Piece] = []
        if self._pending is not None and self._last is not None:
            if now - self._last >= max(self.gap_s, self._vote_gap or 0.0):
                self._vote("last")
                self._vote_gap = None
                self._place(*self._pending, "last", out)
                self._pending = None
        f = self._frame
        if (
            self.timed is False
            and f is not None
            and f.t is not None
            and not f.closed
            and now - f.last_wire >= self.silence()
        ):
            f.closed = True
            out.append(Piece(f.t, [], f.last_arrival, True))
        return out

    def feed(self, packet: Packet, arrival: float, wire: float | None = None) -> list[Piece]:
        """One decoded datagram, stamped ``arrival`` by the receiver and received at
        ``wire`` (default: ``arrival``); the pieces it completes."""
        wire = arrival if wire is None else wire
        out = self.expire(wire)
        gap = math.inf if self._last is None else wire - self._last
        self._last = wire
        if self._vote_gap is not None:
            self._vote("first" if self._vote_gap > gap else "last")
            self._vote_gap = None
        if self._pending is not None:
            self._place(*self._pending, self._votes[-1], out)
            self._pending = None
        if packet.time is not None:
            self.timed = True
            if packet.poses:
                self._bundle(packet.time, packet.poses, arrival, wire, out)
            else:
                self._vote_gap = gap
                if self.order is None:
                    self._pending = (packet.time, arrival, wire)
                else:
                    self._place(packet.time, arrival, wire, self.order, out)
            return out
        for pose in packet.poses:
            self._device(pose, arrival, wire, out)
        return out

    # -- the rules ------------------------------------------------------------------------

    def _vote(self, side: str) -> None:
        self._votes.append(side)
        votes = list(self._votes)
        if self.order is None:
            if len(votes) >= VOTES_TO_SET and all(v == side for v in votes[-VOTES_TO_SET:]):
                self.order = side
        elif sum(v != self.order for v in votes) >= VOTES_TO_TURN:
            self.order = "last" if self.order == "first" else "first"

    def _expected(self) -> frozenset[tuple[str, str]]:
        return frozenset.intersection(*self._recent) if self._recent else frozenset()

    def _complete(self, f: _Open) -> bool:
        expected = self._expected()
        return bool(expected) and expected <= f.names

    def _start(self, frame: _Open | None) -> None:
        """Replace the open frame (remembering the devices of the one it replaces)."""
        old = self._frame
        if old is not None and old.names and old.t is not None:
            self._recent.append(frozenset(old.names))
        self._frame = frame

    def _close_open(self, out: list[Piece]) -> None:
        """Close the open frame if it is not; devices still waiting for a time are lost."""
        f = self._frame
        if f is None:
            return
        if f.t is None:
            self.untimed += len(f.waiting)
            f.waiting = []
        elif not f.closed and f.names:
            f.closed = True
            out.append(Piece(f.t, [], f.last_arrival, True))

    def _place(self, t: float, arrival: float, wire: float, side: str, out: list[Piece]) -> None:
        """A lone time ``t``: ``first`` starts a frame, ``last`` ends the waiting one."""
        f = self._frame
        if side == "first":
            if f is not None and f.t == t and not f.bundle:
                return  # the same time again
            self._close_open(out)
            self._start(_Open(t, wire, wire, arrival))
            return
        if f is not None and f.t is None and f.waiting:
            f.t, f.closed, f.last_wire, f.last_arrival = t, True, wire, arrival
            out.append(Piece(t, f.waiting, arrival, True))
            f.waiting = []
        else:
            self._close_open(out)
        self._start(None)

    def _bundle(self, t: float, poses: list[Pose], arrival: float, wire: float, out: list[Piece]) -> None:
        """A datagram with a time and devices: a frame of its own, or more of the frame at
        the same time (a frame split over datagrams); devices waiting for a time join it."""
        f = self._frame
        if f is not None and f.t == t:
            f.names.update(_key(p) for p in poses)
            f.last_wire, f.last_arrival, f.closed = wire, arrival, True
            out.append(Piece(t, list(poses), arrival, True))
            return
        waiting = f.waiting if f is not None and f.t is None else []
        if f is not None and f.t is None:
            f.waiting = []
        else:
            self._close_open(out)
        names = {_key(p) for p in [*waiting, *poses]}
        self._start(_Open(t, wire, wire, arrival, names, closed=True, bundle=True))
        out.append(Piece(t, [*waiting, *poses], arrival, True))

    def _device(self, pose: Pose, arrival: float, wire: float, out: list[Piece]) -> None:
        """A device without a time in its datagram."""
        f = self._frame
        if f is not None and f.t is not None and self.timed and _key(pose) in f.names:
            # a device again under the same time: the next frame's time was lost; its devices
            # wait, and are dropped when the next time comes
            f = _Open(None, wire, wire, arrival, {_key(pose)}, [pose])
            self._start(f)
            return
        if f is not None and f.t is not None and self.timed:
            # the frame of the latest time (time first, or more of a bundle's frame)
            f.names.add(_key(pose))
            f.last_wire, f.last_arrival = wire, arrival
            close = f.closed or self._complete(f)
            f.closed = close
            out.append(Piece(f.t, [pose], arrival, close))
            return
        if self.timed is False:
            self._untimed_device(pose, arrival, wire, out)
            return
        # waiting for a time (time last, or not known yet)
        if f is not None and _key(pose) in f.names:
            if self.timed is None:  # a device repeated before any time: a sender without time
                self.timed = False
                f.t, f.closed = f.first_wire - self.clock_origin, True
                self._starts.append(f.first_wire)
                out.append(Piece(f.t, f.waiting, f.last_arrival, True))
                f.waiting = []
                self._untimed_device(pose, arrival, wire, out)
                return
            self.untimed += len(f.waiting)  # this frame's time never came (its datagram was lost)
            f = None
        if f is None:
            f = _Open(None, wire, wire, arrival)
            self._start(f)
        f.names.add(_key(pose))
        f.waiting.append(pose)
        f.last_wire, f.last_arrival = wire, arrival

    def _untimed_device(self, pose: Pose, arrival: float, wire: float, out: list[Piece]) -> None:
        """A device of a sender without time: a repeat or a silence starts a new frame."""
        f = self._frame
        if f is None or f.t is None or _key(pose) in f.names or wire - f.last_wire >= self.silence():
            if f is not None and f.t is not None and not f.closed:
                f.closed = True
                out.append(Piece(f.t, [], f.last_arrival, True))
            f = _Open(wire - self.clock_origin, wire, wire, arrival)
            self._start(f)
            self._starts.append(wire)
        f.names.add(_key(pose))
        f.last_wire, f.last_arrival = wire, arrival
        close = f.closed or self._complete(f)
        f.closed = close
        assert f.t is not None  # an untimed sender's frame has its time from its first datagram
        out.append(Piece(f.t, [pose], arrival, close))


def _key(pose: Pose) -> tuple[str, str]:
    """A device as the frame rules count it: its name on its address (a sender may send
    one device on ``/Pos`` and on ``/Pos/Local`` in the same frame)."""
    return pose.tracker, pose.address
