"""Tracker recordings: a plain JSON Lines format, its streaming atomic writer, its reader,
and the replay that turns a recording into the solver's input.

Format (one JSON object per line, UTF-8; ``docs/trackers.md`` has a worked example):

* line 1, the header::

    {"format": "dragposer-trackers", "version": 1, "convention": "project",
     "units": "m", "fps": 60.0, "mapping": {"slots": {...}, "dof": {...}}, "source": "..."}

  ``convention`` says which axes the samples use (:mod:`engine.tracker_io.coords`: our
  writer always writes ``project``; files from elsewhere may say ``unity`` or
  ``openxr`` and are converted on reading). ``fps`` is the nominal rate, ``mapping`` the
  tracker -> joint mapping in force when recording (the reader's default mapping).
* every further line, one sample::

    {"t": 1.016667, "tracker": "head", "pos": [x, y, z], "quat": [w, x, y, z], "valid": true}

  ``t`` is the stream time in seconds; samples sharing a ``t`` form one frame. ``pos``
  in metres; ``quat`` is (w, x, y, z). ``valid: false`` marks a device that is not
  tracking (``pos``/``quat`` may then be null). ``slot`` (the joint it drove) may be
  present; it is informational.
"""

from __future__ import annotations

import contextlib
import json
import math
import threading
from collections.abc import Iterable, Iterator
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from engine import skeleton as sk
from engine.atomic import atomic_path
from engine.errors import UserError
from engine.tracker_io.coords import CONVENTIONS, to_project
from engine.tracker_io.trackers import DEFAULT_TIMEOUT_S, TrackerMapping, TrackerSample, TrackerState
from engine.validation import MAX_LINE_BYTES, check_input_file

if TYPE_CHECKING:
    from engine.sensors import SensorFrame
    from engine.tracker_io.calibration import Calibration
    from engine.tracking.simulate import Tracking

FORMAT = "dragposer-trackers"
VERSION = 1


@dataclass
class Recording:
    """A tracker recording in memory.

    Attributes
    ----------
    samples : list of TrackerSample
        In file order, project frame.
    mapping : TrackerMapping
        The mapping stored in the header.
    fps : float
        Nominal frame rate from the header, frames per second.
    header : dict
        The raw header.
    path : Path or None
    """

    samples: list[TrackerSample]
    mapping: TrackerMapping = field(default_factory=TrackerMapping)
    fps: float = sk.FPS
    header: dict = field(default_factory=dict)
    path: Path | None = None

    def times(self) -> np.ndarray:
        """Frame times (sorted unique sample times), seconds."""
        return np.unique(np.array([s.t for s in self.samples], float))

    @property
    def duration(self) -> float:
        t = self.times()
        return float(t[-1] - t[0]) if t.size else 0.0


def header(fps: float, mapping: TrackerMapping, source: str, **extra: Any) -> dict:
    """The header object our writer puts on line 1."""
    return {
        "format": FORMAT,
        "version": VERSION,
        "convention": "project",
        "units": "m",
        "fps": float(fps),
        "mapping": mapping.to_json(),
        "source": source,
        **extra,
    }


def sample_line(s: TrackerSample, slot: str | None = None) -> str:
    obj: dict[str, Any] = {"t": round(float(s.t), 6), "tracker": s.tracker}
    if slot is not None:
        obj["slot"] = slot
    obj["pos"] = [round(float(v), 6) for v in s.position]
    obj["quat"] = [round(float(v), 7) for v in s.rotation]
    obj["valid"] = bool(s.valid)
    return json.dumps(obj, separators=(",", ":"), allow_nan=False)


class RecordingWriter:
    """Write a recording while it streams: lines go to a temporary file beside the
    target, which replaces the target only on :meth:`close`; :meth:`abort` (or an
    exception inside ``with``) leaves the old target, never a partial one.

    Thread-safe: the receiver thread writes, another thread closes.
    """

    def __init__(self, path: str | Path, head: dict, flush_every: int = 256) -> None:
        self.path = Path(path)
        self._stack = contextlib.ExitStack()
        self._tmp = self._stack.enter_context(atomic_path(self.path))
        self._fh = open(self._tmp, "w", encoding="utf-8")
        self._lock = threading.Lock()
        self._pending = 0
        self._flush_every = flush_every
        self.samples = 0
        self._fh.write(json.dumps(head, separators=(",", ":")) + "\n")

    def write(self, sample: TrackerSample, slot: str | None = None) -> None:
        line = sample_line(sample, slot)
        with self._lock:
            if self._fh.closed:
                return
            self._fh.write(line + "\n")
            self.samples += 1
            self._pending += 1
            if self._pending >= self._flush_every:
                self._fh.flush()
                self._pending = 0

    def close(self) -> None:
        """Finish: the target now holds the whole recording."""
        with self._lock:
            if self._fh.closed:
                return
            self._fh.close()
        self._stack.close()

    def abort(self) -> None:
        """Drop what was written; the target is left as it was."""
        with self._lock:
            if not self._fh.closed:
                self._fh.close()
        err = RuntimeError("recording aborted")
        self._stack.__exit__(RuntimeError, err, None)

    def __enter__(self) -> "RecordingWriter":
        return self

    def __exit__(self, exc_type, exc, tb) -> None:
        if exc_type is None:
            self.close()
        else:
            self.abort()


def write_recording(
    path: str | Path,
    samples: Iterable[TrackerSample],
    fps: float,
    mapping: TrackerMapping | None = None,
    source: str = "",
) -> None:
    """Write a whole recording at once (atomically)."""
    mapping = mapping or TrackerMapping()
    with RecordingWriter(path, header(fps, mapping, source)) as w:
        for s in samples:
            w.write(s, mapping.slot(s.tracker))


def _numbers(obj: dict, key: str, n: int, where: str) -> np.ndarray:
    v = obj.get(key)
    if (
        not isinstance(v, list)
        or len(v) != n
        or not all(isinstance(x, (int, float)) and not isinstance(x, bool) for x in v)
    ):
        raise UserError(f"{where}: field {key!r} must be a list of {n} numbers")
    a = np.array(v, float)
    if not np.all(np.isfinite(a)):
        raise UserError(f"{where}: field {key!r} has a non-finite value")
    return a


def _parse_header(line: str, where: str) -> dict:
    try:
        head = json.loads(line)
    except json.JSONDecodeError as exc:
        raise UserError(f"{where}: header is not JSON ({exc.msg})") from None
    if not isinstance(head, dict) or head.get("format") != FORMAT:
        raise UserError(f'{where}: not a tracker recording (the header needs "format": "{FORMAT}")')
    if head.get("version") != VERSION:
        raise UserError(f"{where}: field 'version': this reader knows version {VERSION}, got {head.get('version')!r}")
    if head.get("convention", "project") not in CONVENTIONS:
        raise UserError(f"{where}: field 'convention' must be one of {', '.join(CONVENTIONS)}")
    fps = head.get("fps", sk.FPS)
    if not isinstance(fps, (int, float)) or not math.isfinite(fps) or not 1 <= fps <= 1000:
        raise UserError(f"{where}: field 'fps' must be a number in [1, 1000], got {fps!r}")
    return head


def read_recording(path: str | Path) -> Recording:
    """Read a recording; samples are converted to the project frame.

    Raises
    ------
    UserError
        For a missing file, a bad header or a bad sample; the message names the file,
        the line and the field.
    """
    path = check_input_file(path, "tracker recording")  # regular file, size limit
    samples: list[TrackerSample] = []
    head: dict | None = None
    try:
        fh = open(path, "rb")
    except OSError as exc:
        raise UserError(f"{path}: cannot read tracker recording ({exc.strerror})") from None
    with fh:
        for lineno, text in enumerate(_lines(fh, path), start=1):
            where = f"{path}:{lineno}"
            if not text.strip():
                continue
            if head is None:
                head = _parse_header(text, where)
                conv = head.get("convention", "project")
                continue
            samples.append(_parse_sample(text, where, conv))
    if head is None:
        raise UserError(f"{path}: empty file (expected a header line)")
    mapping = TrackerMapping()
    if "mapping" in head:
        try:
            m = head["mapping"]
            mapping = TrackerMapping(
                {str(k): str(v) for k, v in m["slots"].items()}, {str(k): int(v) for k, v in m.get("dof", {}).items()}
            )
        except (KeyError, TypeError, ValueError, AttributeError, UserError) as exc:
            raise UserError(f"{path}:1: field 'mapping': {exc}") from None
    return Recording(samples, mapping, float(head.get("fps", sk.FPS)), head, path)


def _lines(fh, path: Path) -> Iterator[str]:
    """The lines of a recording as text; a line that is too long, holds a NUL byte (a binary
    file) or is not UTF-8 is an error naming the file and the line."""
    for lineno, raw in enumerate(iter(lambda: fh.readline(MAX_LINE_BYTES + 1), b""), start=1):
        if len(raw) > MAX_LINE_BYTES:
            raise UserError(f"{path}:{lineno}: line longer than {MAX_LINE_BYTES:,} bytes; not a tracker recording")
        if b"\0" in raw:
            raise UserError(f"{path}:{lineno}: binary data (a NUL byte); a tracker recording is JSON Lines text")
        try:
            yield raw.decode("utf-8")
        except UnicodeDecodeError as exc:
            raise UserError(f"{path}:{lineno}: not UTF-8 text (byte 0x{raw[exc.start]:02x})") from None


def _parse_sample(line: str, where: str, conv: str) -> TrackerSample:
    try:
        obj = json.loads(line)
    except json.JSONDecodeError as exc:
        raise UserError(f"{where}: not JSON ({exc.msg})") from None
    if not isinstance(obj, dict):
        raise UserError(f"{where}: expected a JSON object")
    t = obj.get("t")
    if not isinstance(t, (int, float)) or isinstance(t, bool) or not math.isfinite(t):
        raise UserError(f"{where}: field 't' must be a finite number (seconds)")
    name = obj.get("tracker")
    if not isinstance(name, str) or not name:
        raise UserError(f"{where}: field 'tracker' must be a non-empty string")
    valid = obj.get("valid", True)
    if not isinstance(valid, bool):
        raise UserError(f"{where}: field 'valid' must be true or false")
    if not valid and (obj.get("pos") is None or obj.get("quat") is None):
        return TrackerSample(float(t), name, np.zeros(3), np.array([1.0, 0, 0, 0]), False)
    pos = _numbers(obj, "pos", 3, where)
    quat = _numbers(obj, "quat", 4, where)
    norm = float(np.linalg.norm(quat))
    if norm < 1e-6:
        raise UserError(f"{where}: field 'quat' is zero (not a rotation)")
    pos, quat = to_project(pos, quat / norm, conv)
    return TrackerSample(float(t), name, pos, quat, valid)


def replay(
    samples: Iterable[TrackerSample],
    mapping: TrackerMapping,
    calibration: Calibration | None = None,
    timeout_s: float = DEFAULT_TIMEOUT_S,
    fps: float = sk.FPS,
) -> tuple[Tracking, np.ndarray]:
    """Feed samples through :class:`TrackerState` frame by frame, as the live receiver
    does, and collect the readings as a :class:`~engine.tracking.simulate.Tracking`.

    A frame is every distinct sample time; samples are applied in time order (stable,
    so file order within a frame), duplicates and late samples are skipped as live.

    Returns
    -------
    tracking : Tracking
        F frames, one column per mapped slot seen; slots not seen yet read as
        disconnected.
    times : ndarray (F,)
        Stream time of each frame, seconds.
    """
    from engine.tracking.simulate import Tracking

    ordered = sorted(samples, key=lambda s: s.t)
    state = TrackerState(mapping, timeout_s, calibration)
    frames: list[SensorFrame] = []
    times: list[float] = []
    i = 0
    while i < len(ordered):
        t = ordered[i].t
        while i < len(ordered) and ordered[i].t == t:
            state.update(ordered[i])
            i += 1
        frames.append(state.frame(len(frames), t))
        times.append(t)
    joints = tuple(j for j in sk.JOINT_NAMES if any(j in f.readings for f in frames))
    if not joints:
        raise UserError(
            "the recording has no valid sample of a mapped tracker "
            f"(mapping: {', '.join(f'{k}={v}' for k, v in mapping.slots.items())})"
        )
    n, s = len(frames), len(joints)
    pos = np.zeros((n, s, 3))
    rot = np.tile(np.array([1.0, 0.0, 0.0, 0.0]), (n, s, 1))
    conn = np.zeros((n, s), bool)
    dof = [6] * s
    for fi, f in enumerate(frames):
        for k, j in enumerate(joints):
            r = f.readings.get(j)
            if r is not None:
                pos[fi, k], rot[fi, k], conn[fi, k], dof[k] = r.position, r.rotation, r.connected, r.dof
    return Tracking(joints, tuple(dof), pos, rot, conn, float(fps)), np.array(times)
