"""Typed session events (psygnal signals, as napari's models use).

Each signal of :class:`SessionEvents` carries one frozen payload that says what changed,
with the old value where there is one, so a subscriber can update only what changed and
an undo stack can record the inverse edit::

    session.events.sensors.connect(lambda ev: print(ev.joint, ev.old, ev.new))

All events fire on the thread that called the session method (the GUI thread).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any, Literal

from psygnal import Signal, SignalGroup

from engine.editing.events import ConstraintsChanged

if TYPE_CHECKING:  # annotations only: the command line reads PLAYBACK_PACES without torch
    from engine.motion.clip import Motion
    from engine.sensor_source import SensorSource
    from engine.sensors import Sensor

#: How playback advances: wait for every frame to be solved, or keep the wall clock.
PlaybackPace = Literal["every_frame", "real_time"]
PLAYBACK_PACES: tuple[str, ...] = ("every_frame", "real_time")


@dataclass(frozen=True)
class MotionChanged:
    """A clip was loaded (``path`` None for a generated one)."""

    motion: Motion
    path: Path | None


@dataclass(frozen=True)
class SensorsChanged:
    """The sensor set changed.

    ``joint`` names the one tracker edited (``old`` -> ``new``, either None when it was
    added or removed); ``joint`` None means the whole set was replaced (a preset), with
    ``old_set``/``sensors`` before and after and ``old_preset``/``preset`` their names.
    """

    sensors: tuple[Sensor, ...]
    preset: str
    joint: str | None = None
    old: Sensor | None = None
    new: Sensor | None = None
    old_set: tuple[Sensor, ...] = ()
    old_preset: str = ""


@dataclass(frozen=True)
class SettingsChanged:
    """Optimizer settings changed: ``changed`` the new values, ``old`` the previous ones."""

    changed: dict[str, Any]
    old: dict[str, Any] = field(default_factory=dict)


@dataclass(frozen=True)
class MethodChanged:
    """The reconstruction method or its ghosts changed. ``refused``: the engine kept
    ``method`` when asked for ``old_method`` (the session mirrors it; nothing switches)."""

    method: str
    ghosts: tuple[str, ...]
    old_method: str = ""
    old_ghosts: tuple[str, ...] = ()
    refused: bool = False


@dataclass(frozen=True)
class PlaybackChanged:
    """Play/pause, speed (x real time), loop or pace changed."""

    playing: bool
    speed: float
    loop: bool
    pace: str


@dataclass(frozen=True)
class SourceChanged:
    """Sensors now come from ``source`` (a tracker recording or a live stream, see
    :class:`engine.sensor_source.SensorSource`) instead of a clip; there is no ground truth. ``name`` says
    which (a file name or an address); ``live`` is True for a stream that grows."""

    source: SensorSource
    name: str
    live: bool


class SessionEvents(SignalGroup):
    """The session's signals; connect with ``session.events.NAME.connect(callback)``."""

    motion = Signal(MotionChanged)
    source = Signal(SourceChanged)
    sensors = Signal(SensorsChanged)
    constraints = Signal(ConstraintsChanged)
    settings = Signal(SettingsChanged)
    method = Signal(MethodChanged)
    frame = Signal(int)
    playback = Signal(PlaybackChanged)
