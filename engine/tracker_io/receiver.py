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
  sender restarted; the state starts over).

A *frame* is each new, larger stream time (``/VMC/Ext/T``, or the arrival time when the
sender sends none). Consumers call :meth:`VMCReceiver.wait_frame` to get the newest frame
with the sensor readings at that moment; frames that arrive while a consumer is busy are
superseded, which is how a realtime solver that falls behind skips frames.
"""

from __future__ import annotations

import socket
import threading
import time
from collections import deque
from collections.abc import Callable
from dataclasses import asdict, dataclass

from engine.errors import UserError
from engine.tracker_io.coords import CONVENTIONS
from engine.methods import SensorFrame
from engine.tracker_io.recording import RecordingWriter
from engine.tracker_io.trackers import DEFAULT_TIMEOUT_S, TrackerMapping, TrackerSample, TrackerState
from engine.tracker_io.vmc import ParseError, decode_packet

#: A stream clock that goes back by more than this (seconds) means the sender restarted.
RESTART_S = 1.0
#: Default VMC port (the protocol's performer -> marionette port).
DEFAULT_PORT = 39539


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
    frames: int = 0
    packet_rate_hz: float = 0.0

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
    """

    index: int
    t: float
    arrival: float
    sensors: SensorFrame


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
    """

    def __init__(self, host: str = "127.0.0.1", port: int = DEFAULT_PORT, mapping: TrackerMapping | None = None,
                 convention: str = "unity", timeout_s: float = DEFAULT_TIMEOUT_S,
                 recorder: RecordingWriter | None = None,
                 on_frame: Callable[[LiveFrame], None] | None = None) -> None:  # fmt: skip
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
        self._sock.settimeout(0.05)
        self.host, self.port = self._sock.getsockname()[:2]
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None
        self._frame: LiveFrame | None = None
        self._max_t: float | None = None
        self._t0 = time.perf_counter()
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
            try:
                data, _ = self._sock.recvfrom(65535)
            except TimeoutError:
                continue
            except OSError:
                if self._stop.is_set():
                    break
                continue
            self._handle(data, time.perf_counter())

    def _handle(self, data: bytes, arrival: float) -> None:
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
            if packet.time is not None:
                t = packet.time
            elif self._max_t is not None and not packet.poses:
                return
            else:
                t = arrival - self._t0
            if self._max_t is not None and t < self._max_t - RESTART_S:
                st.restarts += 1
                self.state = TrackerState(self.state.mapping, self.state.timeout_s, self.state.calibration)
                self._max_t = None
            accepted = 0
            for pose in packet.poses:
                sample = TrackerSample(t, pose.tracker, pose.position, pose.rotation, True)
                result = self.state.update(sample)
                if result == "duplicate":
                    st.duplicates += 1
                    continue
                if result == "late":
                    st.late += 1
                    continue
                st.samples += 1
                accepted += 1
                slot = self.state.mapping.slot(pose.tracker)
                if slot is None:
                    st.unmapped += 1
                    self._unmapped_names.add(pose.tracker)
                if self.recorder is not None:
                    self.recorder.write(sample, slot)
            if accepted and (self._max_t is None or t > self._max_t):
                self._max_t = t
                st.frames += 1
                self._frame = LiveFrame(st.frames, t, arrival, self.state.frame(st.frames, t))
                self._lock.notify_all()
                if self.on_frame is not None:
                    self.on_frame(self._frame)
            elif accepted and self._frame is not None and t == self._max_t:
                # the rest of a frame split over several datagrams: same frame, newer data
                self._frame = LiveFrame(self._frame.index, t, arrival, self.state.frame(self._frame.index, t))
