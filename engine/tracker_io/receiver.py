"""The live VMC receiver: a UDP socket read on its own thread.

Every datagram is timestamped on arrival (``time.perf_counter``), decoded
(:mod:`engine.tracker_io.vmc`) and applied to a :class:`TrackerState`. Bad input is
counted, never fatal:

* a datagram that is not OSC -> ``malformed_packets``;
* a pose message with wrong arguments -> ``malformed_messages``;
* a sample no newer than the tracker's newest -> ``duplicates`` (same time) or
  ``late`` (older); it does not change the state;
* a tracker the mapping does not know -> ``unmapped`` (recorded, not solved);
* the stream clock jumping back by more than :data:`RESTART_S` -> ``restarts`` (the
  sender restarted; the state starts over);
* devices whose frame's time never came -> ``untimed`` (not applied).

Which datagrams make up a *frame*, and its stream time, comes from the stream's structure
(:mod:`engine.tracker_io.framing`: one bundle per frame, or one message per datagram with
``/VMC/Ext/T`` first, last or absent). A frame is published when it closes, with how many
mapped devices sent a sample for it (:attr:`LiveFrame.fresh`). Consumers call
:meth:`VMCReceiver.wait_frame` to get the newest frame with the sensor readings at that
moment; frames that arrive while a consumer is busy are superseded, which is how a
realtime solver that falls behind skips frames.
"""

from __future__ import annotations

import socket
import struct
import sys
import threading
import time
from collections import deque
from collections.abc import Callable
from dataclasses import asdict, dataclass

from engine.errors import UserError
from engine.methods import SensorFrame
from engine.tracker_io.coords import CONVENTIONS
from engine.tracker_io.framing import FRAME_GAP_S, FrameAssembler, Piece
from engine.tracker_io.recording import RecordingWriter
from engine.tracker_io.trackers import DEFAULT_TIMEOUT_S, TrackerMapping, TrackerSample, TrackerState
from engine.tracker_io.vmc import ParseError, decode_packet

#: A stream clock that goes back by more than this (seconds) means the sender restarted.
RESTART_S = 1.0
#: Default VMC port (the protocol's performer -> marionette port).
DEFAULT_PORT = 39539
#: Linux's ``SO_TIMESTAMPNS`` (the socket module does not export it): the kernel stamps
#: each datagram with its receive time (``struct timespec``, wall clock).
_SO_TIMESTAMPNS = getattr(socket, "SO_TIMESTAMPNS", 35 if sys.platform.startswith("linux") else None)
_TIMESPEC = struct.Struct("ll")


@dataclass
class ReceiverStats:
    """Counters of a receiver (all since start)."""

    packets: int = 0
    bytes: int = 0
    malformed_packets: int = 0
    malformed_messages: int = 0
    other_messages: int = 0
    samples: int = 0
    duplicates: int = 0
    late: int = 0
    unmapped: int = 0
    restarts: int = 0
    untimed: int = 0
    frames: int = 0
    packet_rate_hz: float = 0.0
    packet_shape: str = ""

    def to_json(self) -> dict:
        return asdict(self)


@dataclass(frozen=True)
class LiveFrame:
    """The newest frame a consumer gets from :meth:`VMCReceiver.wait_frame`.

    Attributes
    ----------
    index : int
        Frame counter of the receiver (1 = first frame); gaps mean superseded frames.
    t : float
        Stream time, seconds.
    arrival : float
        ``time.perf_counter()`` when the frame's newest datagram arrived.
    sensors : SensorFrame
        Readings of the mapped trackers at ``t`` (calibration applied if set).
    fresh : int
        Mapped devices that sent a sample for this frame.
    devices : int
        Mapped devices seen since the stream (re)started; ``fresh < devices`` means the
        sender left some out of this frame.
    """

    index: int
    t: float
    arrival: float
    sensors: SensorFrame
    fresh: int = 0
    devices: int = 0


def parse_listen(text: str) -> tuple[str, int]:
    """``PORT`` (all interfaces) or ``HOST:PORT`` -> (host, port)."""
    host, _, port = str(text).rpartition(":")
    try:
        p = int(port)
    except ValueError:
        raise UserError(f"--listen {text!r}: expected PORT or HOST:PORT") from None
    if not 0 <= p <= 65535:
        raise UserError(f"--listen {text!r}: port must be in [0, 65535]")
    return host or "0.0.0.0", p


class VMCReceiver:
    """Receive VMC on ``host:port`` on a background thread.

    Parameters
    ----------
    host, port : str, int
        Where to listen; port 0 picks a free port (see :attr:`port`).
    mapping : TrackerMapping, optional
    convention : str
        Axes of the incoming poses (VMC: ``unity``; :mod:`engine.tracker_io.coords`).
    timeout_s : float
        Seconds without a valid sample before a tracker reads as lost.
    recorder : RecordingWriter, optional
        Every accepted sample is written to it (raw tracker pose, project frame); may be
        swapped while running (:attr:`recorder`).
    on_frame : callable, optional
        Called on the receiver thread with every new :class:`LiveFrame` (keep it short).
    frame_gap_s : float
        Silence that closes a frame sent as separate messages (:mod:`~engine.tracker_io.framing`).
    """

    def __init__(
        self,
        host: str = "127.0.0.1",
        port: int = DEFAULT_PORT,
        mapping: TrackerMapping | None = None,
        convention: str = "unity",
        timeout_s: float = DEFAULT_TIMEOUT_S,
        recorder: RecordingWriter | None = None,
        on_frame: Callable[[LiveFrame], None] | None = None,
        frame_gap_s: float = FRAME_GAP_S,
    ) -> None:
        if convention not in CONVENTIONS:
            raise UserError(f"unknown coordinate convention {convention!r}; known: {', '.join(CONVENTIONS)}")
        self.state = TrackerState(mapping, timeout_s)
        self.convention = convention
        self.recorder = recorder
        self.on_frame = on_frame
        self.stats = ReceiverStats()
        self._lock = threading.Condition()
        self._sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        self._sock.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, 1 << 20)
        try:
            self._sock.bind((host, port))
        except OSError as exc:
            self._sock.close()
            raise UserError(f"cannot listen on {host}:{port} ({exc.strerror})") from None
        self._wire_stamps = False
        if _SO_TIMESTAMPNS is not None:
            try:
                self._sock.setsockopt(socket.SOL_SOCKET, _SO_TIMESTAMPNS, 1)
                self._wire_stamps = True
            except OSError:  # no kernel stamps here: the receiver's own stamps serve
                pass
        self.host, self.port = self._sock.getsockname()[:2]
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None
        self._frame: LiveFrame | None = None
        self._max_t: float | None = None
        self._t0 = time.perf_counter()
        self._assembler = FrameAssembler(frame_gap_s, self._t0)
        self._acc_t: float | None = None  # time of the frame whose samples are being counted
        self._acc = 0  # samples accepted for it since it was last published
        self._arrivals: deque[float] = deque(maxlen=512)
        self._unmapped_names: set[str] = set()

    # -- lifecycle -------------------------------------------------------------------

    def start(self) -> "VMCReceiver":
        self._thread = threading.Thread(target=self._run, name=f"vmc-receiver:{self.port}", daemon=True)
        self._thread.start()
        return self

    def stop(self) -> None:
        """Stop the thread and close the socket (the recorder is the caller's)."""
        self._stop.set()
        if self._thread is not None:
            self._thread.join(timeout=2.0)
        self._sock.close()
        with self._lock:
            self._lock.notify_all()

    def __enter__(self) -> "VMCReceiver":
        return self.start()

    def __exit__(self, *exc) -> None:
        self.stop()

    # -- consumers -------------------------------------------------------------------

    def wait_frame(self, after: int = 0, timeout: float | None = None) -> LiveFrame | None:
        """The newest frame with ``index > after``; waits up to ``timeout`` seconds
        (None: forever, until :meth:`stop`). Returns None on timeout or stop."""
        deadline = None if timeout is None else time.perf_counter() + timeout
        with self._lock:
            while self._frame is None or self._frame.index <= after:
                if self._stop.is_set():
                    return None
                left = None if deadline is None else deadline - time.perf_counter()
                if left is not None and left <= 0:
                    return None
                self._lock.wait(0.1 if left is None else min(left, 0.1))
            return self._frame

    def set_calibration(self, calibration) -> None:
        """Apply tracker-to-joint offsets to readings from the next frame on."""
        with self._lock:
            self.state.calibration = calibration

    def snapshot_stats(self) -> ReceiverStats:
        with self._lock:
            s = ReceiverStats(**asdict(self.stats))
            s.untimed, s.packet_shape = self._assembler.untimed, self._assembler.shape
        if len(self._arrivals) >= 2:
            span = self._arrivals[-1] - self._arrivals[0]
            s.packet_rate_hz = (len(self._arrivals) - 1) / span if span > 0 else 0.0
        return s

    @property
    def running(self) -> bool:
        """True while the receiver thread reads the socket."""
        return self._thread is not None and self._thread.is_alive() and not self._stop.is_set()

    @property
    def last_arrival(self) -> float | None:
        """``time.perf_counter()`` of the newest frame, or None before the first."""
        f = self._frame
        return None if f is None else f.arrival

    @property
    def unmapped_names(self) -> list[str]:
        return sorted(self._unmapped_names)

    # -- the thread ------------------------------------------------------------------

    def _run(self) -> None:
        while not self._stop.is_set():
            with self._lock:
                due = self._assembler.deadline()
            # wake for the assembler's silence rules, else now and then to see stop
            wait = 0.05 if due is None else min(max(due - time.perf_counter(), 1e-4), 0.05)
            try:
                data, ancillary = self._receive(wait)
            except TimeoutError:
                # Datagrams may have come while this thread waited for the interpreter after
                # the timeout: they go first (their wire time places the silence), and the
                # silence rules run at "now" only when none is waiting.
                now = time.perf_counter()
                try:
                    data, ancillary = self._receive(0.0)
                except (BlockingIOError, TimeoutError):
                    with self._lock:
                        self._apply(self._assembler.expire(now))
                    continue
                except OSError:
                    continue
            except OSError:
                if self._stop.is_set():
                    break
                continue
            arrival = time.perf_counter()
            self._handle(data, arrival, _wire_time(ancillary, arrival))

    def _receive(self, timeout: float) -> tuple[bytes, list]:
        """One datagram and its ancillary data (the kernel's stamp), waiting ``timeout`` s."""
        self._sock.settimeout(timeout)
        if self._wire_stamps:
            data, ancillary, _, _ = self._sock.recvmsg(65535, socket.CMSG_SPACE(_TIMESPEC.size))
            return data, ancillary
        return self._sock.recvfrom(65535)[0], []

    def _handle(self, data: bytes, arrival: float, wire: float | None = None) -> None:
        """One datagram, stamped ``arrival`` here and received by the kernel at ``wire``
        (both ``perf_counter`` time; :mod:`~engine.tracker_io.framing`)."""
        self._arrivals.append(arrival)
        try:
            packet = decode_packet(data, self.convention)
        except ParseError:
            packet = None
        except Exception:  # python-osc raises other errors on some garbage; never fatal
            packet = None
        with self._lock:
            st = self.stats
            st.packets += 1
            st.bytes += len(data)
            if packet is None:
                st.malformed_packets += 1
                return
            st.malformed_messages += packet.malformed
            st.other_messages += packet.other
            self._apply(self._assembler.feed(packet, arrival, wire))

    def _apply(self, pieces: list[Piece]) -> None:
        """Apply the assembler's pieces to the state (lock held); publish closed frames."""
        st = self.stats
        for pc in pieces:
            t = pc.t
            if self._max_t is not None and t < self._max_t - RESTART_S:
                st.restarts += 1
                self.state = TrackerState(self.state.mapping, self.state.timeout_s, self.state.calibration)
                self._max_t = None
            if t != self._acc_t:
                self._acc_t, self._acc = t, 0
            for pose in pc.poses:
                sample = TrackerSample(t, pose.tracker, pose.position, pose.rotation, True)
                result = self.state.update(sample)
                if result == "duplicate":
                    st.duplicates += 1
                    continue
                if result == "late":
                    st.late += 1
                    continue
                st.samples += 1
                self._acc += 1
                slot = self.state.mapping.slot(pose.tracker)
                if slot is None:
                    st.unmapped += 1
                    self._unmapped_names.add(pose.tracker)
                if self.recorder is not None:
                    self.recorder.write(sample, slot)
            if pc.close and self._acc:
                self._acc = 0
                self._publish(t, pc.arrival)

    def _publish(self, t: float, arrival: float) -> None:
        mapped = [n for n in self.state.last_t if self.state.mapping.slot(n) is not None]
        fresh = sum(1 for n in mapped if self.state.last_t[n] == t)
        if self._max_t is None or t > self._max_t:
            self._max_t = t
            self.stats.frames += 1
            self._frame = LiveFrame(
                self.stats.frames, t, arrival, self.state.frame(self.stats.frames, t), fresh, len(mapped)
            )
            self._lock.notify_all()
            if self.on_frame is not None:
                self.on_frame(self._frame)
        elif self._frame is not None and t == self._max_t:
            # more of a published frame (a device after it closed): same frame, newer data
            i = self._frame.index
            self._frame = LiveFrame(i, t, arrival, self.state.frame(i, t), fresh, len(mapped))


def _wire_time(ancillary: list, arrival: float) -> float:
    """The kernel's receive stamp of a datagram on the ``perf_counter`` timeline (``arrival``
    when there is none)."""
    for level, kind, payload in ancillary:
        if level == socket.SOL_SOCKET and kind == _SO_TIMESTAMPNS and len(payload) >= _TIMESPEC.size:
            sec, nsec = _TIMESPEC.unpack_from(payload)
            return min(arrival, arrival - (time.time() - (sec + 1e-9 * nsec)))
    return arrival
