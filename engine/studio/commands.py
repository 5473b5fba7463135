"""Commands the session sends to the engine thread: small frozen dataclasses.

They carry values, never live objects the GUI keeps changing: sensors are frozen
:class:`~engine.sensors.Sensor` s and constraints are objects the session never modifies
after publishing them (an edit replaces the object), so the engine thread uses them
directly, without copies and without a lock.

Every command derives from :class:`Command`; the engine thread dispatches on the
command's class through :data:`HANDLERS`, and a test checks that every class defined
here has a handler. Adding a command: a frozen dataclass here, and a method of
:class:`~engine.studio.thread.EngineThread` decorated with ``@handles(TheCommand)``.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

from engine.motion.clip import Motion
from engine.sensor_source import SensorSource
from engine.sensors import Sensor
from engine.solver.settings_edit import SettingsEdit


@dataclass(frozen=True)
class Command:
    """Base of the engine thread's commands; never sent itself."""


@dataclass(frozen=True)
class SetMotion(Command):
    """Solve ``motion``; ``opened`` numbers this clip, source or method among those the
    session opened, and the snapshots carry the newest number the engine took
    (``Snapshot.opened``), so views can tell a snapshot of what came before."""

    motion: Motion
    opened: int = 0


@dataclass(frozen=True)
class SetSensors(Command):
    sensors: tuple[Sensor, ...]


@dataclass(frozen=True)
class SetConstraints(Command):
    """The whole user constraint list (the session's own objects, see the module doc)."""

    constraints: tuple[Any, ...]


@dataclass(frozen=True)
class SetSettings(Command):
    """Settings the studio set explicitly (checked, immutable), merged into the earlier
    ones; with ``replace``, instead of them (an undo puts back a setting left unset)."""

    values: SettingsEdit
    replace: bool = False


@dataclass(frozen=True)
class SetMethod(Command):
    name: str
    ghosts: tuple[str, ...] = ()
    opened: int = 0  # as SetMotion's


@dataclass(frozen=True)
class SetGhosts(Command):
    """Other methods drawn beside the shown one; the shown method and its state stay."""

    ghosts: tuple[str, ...] = ()


@dataclass(frozen=True)
class Seek(Command):
    frame: int


@dataclass(frozen=True)
class Play(Command):
    """Start playback at ``speed`` x real time.

    ``pace`` ``"every_frame"`` solves every clip frame in order and lets the clock wait
    for the solver; ``"real_time"`` keeps the clock and skips frames the solver missed.
    """

    speed: float = 1.0
    loop: bool = True
    pace: str = "every_frame"


@dataclass(frozen=True)
class Pause(Command):
    pass


@dataclass(frozen=True)
class Step(Command):
    delta: int = 1


@dataclass(frozen=True)
class DecodeLatent(Command):
    """Decode ``latent`` (L,) with the method's decoder; the optimizer is paused meanwhile."""

    latent: np.ndarray


@dataclass(frozen=True)
class InspectLatent(Command):
    """Compute the latent detail of the last solved frame (term forces, dimension sweep,
    and ``joint``'s most influential dimensions when given); published in the snapshot's
    ``latent_detail`` (docs/latent.md). The frame is not solved again."""

    joint: str = ""


@dataclass(frozen=True)
class Stop(Command):
    pass


@dataclass(frozen=True)
class SetSource(Command):
    """Read sensors from ``source`` (an :class:`engine.sensor_source.SensorSource`)
    instead of the clip; the session's sensor settings still apply."""

    source: SensorSource
    opened: int = 0  # as SetMotion's


#: The engine thread's handler of each command class, ``handler(thread, command,
#: was_dirty)`` (``was_dirty``: a solve was due before the command); filled by
#: :func:`handles` when :mod:`engine.studio.thread` is imported.
HANDLERS: dict[type[Command], Callable[[Any, Any, bool], None]] = {}


def handles(*types: type[Command]) -> Callable[[Callable], Callable]:
    """Register the decorated engine-thread method as the handler of ``types``."""

    def register(handler: Callable) -> Callable:
        for t in types:
            if t in HANDLERS:
                raise TypeError(f"two engine handlers for {t.__name__}")
            HANDLERS[t] = handler
        return handler

    return register


def handler_for(command_type: type) -> Callable[[Any, Any, bool], None] | None:
    """The handler of ``command_type`` (its own, or its nearest base class's), or None."""
    return next((HANDLERS[c] for c in command_type.__mro__ if c in HANDLERS), None)


def check_command(command: Any) -> None:
    """Raise ``TypeError`` unless the engine has a handler for ``command``."""
    if handler_for(type(command)) is None:
        known = ", ".join(sorted(c.__name__ for c in HANDLERS))
        raise TypeError(f"the engine has no handler for {type(command).__name__!r}; it takes {known}")
