"""Commands the session sends to the engine thread: small frozen dataclasses.

They carry values, never live objects the GUI keeps changing: sensors are frozen
:class:`~engine.sensors.Sensor` s and constraints are objects the session never modifies
after publishing them (an edit replaces the object), so the engine thread uses them
directly, without copies and without a lock.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from engine.motion.clip import Motion
from engine.sensor_source import SensorSource
from engine.sensors import Sensor
from engine.solver.settings import SettingsEdit


@dataclass(frozen=True)
class SetMotion:
    motion: Motion


@dataclass(frozen=True)
class SetSensors:
    sensors: tuple[Sensor, ...]


@dataclass(frozen=True)
class SetConstraints:
    """The whole user constraint list (the session's own objects, see the module doc)."""

    constraints: tuple[Any, ...]


@dataclass(frozen=True)
class SetSettings:
    """Settings the studio set explicitly (checked, immutable), merged into the earlier
    ones; with ``replace``, instead of them (an undo puts back a setting left unset)."""

    values: SettingsEdit
    replace: bool = False


@dataclass(frozen=True)
class SetMethod:
    name: str
    ghosts: tuple[str, ...] = ()


@dataclass(frozen=True)
class Seek:
    frame: int


@dataclass(frozen=True)
class Play:
    """Start playback at ``speed`` x real time.

    ``pace`` ``"every_frame"`` solves every clip frame in order and lets the clock wait
    for the solver; ``"real_time"`` keeps the clock and skips frames the solver missed.
    """

    speed: float = 1.0
    loop: bool = True
    pace: str = "every_frame"


@dataclass(frozen=True)
class Pause:
    pass


@dataclass(frozen=True)
class Step:
    delta: int = 1


@dataclass(frozen=True)
class DecodeLatent:
    """Decode ``latent`` (L,) with the method's decoder; the optimizer is paused meanwhile."""

    latent: np.ndarray


@dataclass(frozen=True)
class InspectLatent:
    """Compute the latent detail of the last solved frame (term forces, dimension sweep,
    and ``joint``'s most influential dimensions when given); published in the snapshot's
    ``latent_detail`` (docs/latent.md). The frame is not solved again."""

    joint: str = ""


@dataclass(frozen=True)
class Stop:
    pass


@dataclass(frozen=True)
class SetSource:
    """Read sensors from ``source`` (an :class:`engine.sensor_source.SensorSource`)
    instead of the clip; the session's sensor settings still apply."""

    source: SensorSource
