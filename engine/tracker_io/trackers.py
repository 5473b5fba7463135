"""Tracker samples, the tracker-name -> body-slot mapping, and the state that turns a
stream of samples into the solver's :class:`~engine.methods.SensorFrame`.

A *tracker* is a device with a name (``head``, ``left_hand``, a serial number...). The
:class:`TrackerMapping` assigns trackers to *slots*, the canonical joints the solver has
sensors for (``upperneck``, ``lwrist``, ``rwrist``, ``root``, ``lankle``, ``rankle``;
any canonical joint is allowed). :class:`TrackerState` keeps the newest sample of every
tracker and answers "what do the sensors read at stream time t": a slot whose tracker
sent nothing valid for :attr:`TrackerState.timeout_s` seconds reads as disconnected, and
its reading then holds the last value, exactly as the simulated trackers do
(:mod:`engine.tracking.simulate`). Live input and recorded replay both go through this
class, so a recording replayed offline feeds the solver the same readings the live run
had.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from engine import skeleton as sk
from engine.errors import UserError
from engine.input_files import read_json
from engine.sensors import Sensor, SensorFrame

if TYPE_CHECKING:
    from engine.tracker_io.calibration import Calibration

#: Seconds without a valid sample after which a tracker counts as lost.
DEFAULT_TIMEOUT_S = 0.25

#: Tracker names the sender uses and the receiver maps by default (name -> joint).
DEFAULT_SLOTS: dict[str, str] = {
    "head": "upperneck",
    "left_hand": "lwrist",
    "right_hand": "rwrist",
    "hips": "root",
    "left_foot": "lankle",
    "right_foot": "rankle",
}


@dataclass(frozen=True)
class TrackerSample:
    """One pose of one tracker, already in the project's frame.

    Attributes
    ----------
    t : float
        Stream time, seconds (the sender's clock when it sends one, else arrival time).
    tracker : str
        Device name as the source calls it.
    position : ndarray (3,)
        Metres, project frame (Z up).
    rotation : ndarray (4,)
        Orientation (w, x, y, z), project frame.
    valid : bool
        False when the source says the device is not tracking.
    """

    t: float
    tracker: str
    position: np.ndarray
    rotation: np.ndarray
    valid: bool = True


@dataclass
class TrackerMapping:
    """Which tracker drives which body slot, and with how many DoF.

    Attributes
    ----------
    slots : dict of str -> str
        Tracker name -> canonical joint.
    dof : dict of str -> int
        Tracker name -> 6 (position + rotation) or 3 (position only); default 6.
    """

    slots: dict[str, str] = field(default_factory=lambda: dict(DEFAULT_SLOTS))
    dof: dict[str, int] = field(default_factory=dict)

    def __post_init__(self) -> None:
        joints = list(self.slots.values())
        for name, joint in self.slots.items():
            if joint not in sk.JOINT_INDEX:
                raise UserError(
                    f"tracker mapping: {name!r} -> unknown joint {joint!r}; valid joints: {', '.join(sk.JOINT_NAMES)}"
                )
            if joints.count(joint) > 1:
                raise UserError(f"tracker mapping: joint {joint!r} is driven by more than one tracker")
        for name, d in self.dof.items():
            if d not in (3, 6):
                raise UserError(f"tracker mapping: {name!r}: dof must be 3 or 6, got {d}")

    def slot(self, tracker: str) -> str | None:
        """The joint ``tracker`` drives, or None when it is not mapped."""
        return self.slots.get(tracker)

    def dof_of(self, tracker: str) -> int:
        return self.dof.get(tracker, 6)

    @classmethod
    def parse(cls, text: str) -> "TrackerMapping":
        """``"head=upperneck,hips=root,puck3=lankle:3"`` (a ``:3`` suffix: position only),
        or the path of a JSON file ``{"slots": {...}, "dof": {...}}``; the default
        mapping for an empty string."""
        text = text.strip()
        if not text:
            return cls()
        if text.endswith(".json") or Path(text).is_file():
            return cls.load(text)
        slots: dict[str, str] = {}
        dof: dict[str, int] = {}
        for item in (t.strip() for t in text.split(",") if t.strip()):
            name, eq, joint = item.partition("=")
            if not eq or not name.strip() or not joint.strip():
                raise UserError(f"tracker mapping item {item[:60]!r}: expected NAME=JOINT[:3]")
            joint, _, d = joint.strip().partition(":")
            slots[name.strip()] = joint
            if d:
                if d not in ("3", "6"):
                    raise UserError(f"tracker mapping item {item[:60]!r}: DoF suffix must be :3 or :6")
                dof[name.strip()] = int(d)
        return cls(slots, dof)

    @classmethod
    def load(cls, path: str | Path) -> "TrackerMapping":
        """Read a mapping file (JSON: ``{"slots": {name: joint}, "dof": {name: 3|6}}``)."""
        path = Path(path)
        data = read_json(path, "tracker mapping")  # regular file, size, UTF-8, JSON syntax with line
        try:
            slots = {str(k): str(v) for k, v in data["slots"].items()}
            dof = {str(k): int(v) for k, v in data.get("dof", {}).items()}
        except (ValueError, KeyError, TypeError, AttributeError) as exc:
            raise UserError(
                f"{path}: not a tracker mapping ({type(exc).__name__}: {exc}); "
                'expected {"slots": {"head": "upperneck", ...}, "dof": {...}}'
            ) from exc
        try:
            return cls(slots, dof)
        except UserError as exc:
            raise UserError(f"{path}: {exc}") from None

    def to_json(self) -> dict:
        return {"slots": dict(self.slots), "dof": dict(self.dof)}


class TrackerState:
    """The newest sample of every tracker, and the sensor readings it implies.

    Parameters
    ----------
    mapping : TrackerMapping
    timeout_s : float
        A tracker is lost when its newest valid sample is older than this, seconds.
    calibration : Calibration, optional
        Tracker-to-joint offsets applied to every reading (see
        :mod:`engine.tracker_io.calibration`).
    """

    def __init__(
        self,
        mapping: TrackerMapping | None = None,
        timeout_s: float = DEFAULT_TIMEOUT_S,
        calibration: Calibration | None = None,
    ) -> None:
        self.mapping = mapping or TrackerMapping()
        self.timeout_s = float(timeout_s)
        self.calibration = calibration
        self.latest: dict[str, TrackerSample] = {}  # newest valid sample per tracker
        self.last_t: dict[str, float] = {}  # newest sample time per tracker, valid or not
        self.valid: dict[str, bool] = {}

    def update(self, sample: TrackerSample) -> str:
        """Take one sample. Returns ``"ok"``, ``"duplicate"`` (same time as the newest
        sample of that tracker) or ``"late"`` (older than it); only ``"ok"`` changes
        the state."""
        last = self.last_t.get(sample.tracker)
        if last is not None and sample.t <= last:
            return "duplicate" if sample.t == last else "late"
        self.last_t[sample.tracker] = sample.t
        self.valid[sample.tracker] = sample.valid
        if sample.valid:
            self.latest[sample.tracker] = sample
        return "ok"

    def frame(self, index: int, t: float) -> SensorFrame:
        """Sensor readings of the mapped trackers at stream time ``t``.

        Trackers never seen are absent; a tracker that is invalid or older than the
        timeout reads as disconnected and holds its last valid value.
        """
        readings: dict[str, Sensor] = {}
        for name, s in self.latest.items():
            joint = self.mapping.slot(name)
            if joint is None:
                continue
            dof = self.mapping.dof_of(name)
            pos, rot = s.position, s.rotation
            if self.calibration is not None:
                pos, rot = self.calibration.apply(joint, pos, rot, dof)
            connected = bool(self.valid.get(name, False)) and (t - s.t) <= self.timeout_s
            readings[joint] = Sensor(
                joint, np.array(pos, float), np.array(rot if dof == 6 else (1.0, 0.0, 0.0, 0.0), float), dof, connected
            )
        return SensorFrame(index, readings)
