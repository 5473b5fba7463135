"""The caller's edits to a DragPoser method, and the settings a frame runs with.

:class:`CallerEdits` takes the caller's edits between frames (settings by name, user
constraints, tracker weights). :class:`FrameSettings` holds the caller's :class:`~engine.solver.OptimizerSettings` (edited
by name with :meth:`~FrameSettings.configure`, applied from the next frame) and which
fields the caller chose; each frame then runs with those completed by the connected
sensor set's profile (:func:`engine.solver.profiles.effective`) for the fields the caller
left alone.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Iterable
from typing import Any

from engine.constraints import Constraint
from engine.errors import UserError
from engine.methods.dragposer_parts import TrackerTerms, UserConstraints
from engine.solver import OptimizerSettings
from engine.solver.profiles import effective


class FrameSettings:
    """The caller's settings and the per-frame settings derived from them.

    Parameters
    ----------
    settings : OptimizerSettings, optional
        Edited in place by :meth:`configure` (callers may hold the object).

    Attributes
    ----------
    explicit : set of str
        Settings fields the caller chose, kept against the sensor-set profiles.
    """

    def __init__(self, settings: OptimizerSettings | None = None) -> None:
        self.settings = settings or OptimizerSettings()
        defaults = OptimizerSettings()
        self.explicit: set[str] = {
            f.name
            for f in dataclasses.fields(OptimizerSettings)
            if getattr(self.settings, f.name) != getattr(defaults, f.name)
        }
        self._cache: dict[tuple, OptimizerSettings] = {}

    def configure(self, **values: Any) -> None:
        """Change settings by name; applied from the next frame. Unknown names raise
        :class:`UserError` after the known ones are applied."""
        known = {f.name for f in dataclasses.fields(OptimizerSettings)}
        new = dataclasses.replace(self.settings, **{k: v for k, v in values.items() if k in known})
        self.settings.__dict__.update(new.__dict__)  # keep the object: callers may hold it
        self.explicit |= set(values) & known
        unknown = sorted(set(values) - known)
        if unknown:
            raise UserError(f"unknown optimizer setting(s): {', '.join(unknown)}")

    def for_sensors(self, live: tuple[str, ...], hip_rotation: bool) -> OptimizerSettings:
        """:func:`engine.solver.profiles.effective` for the connected sensors ``live``,
        kept per (settings, sensor set): building and validating the settings object every
        frame cost more than the lookup."""
        key = (tuple(vars(self.settings).values()), live, frozenset(self.explicit), hip_rotation)
        s = self._cache.get(key)
        if s is None:
            if len(self._cache) > 64:
                self._cache.clear()
            s = self._cache[key] = effective(self.settings, live, self.explicit, hip_rotation)
        return s

    def forget(self) -> None:
        """Drop the per-clip cache (a new clip)."""
        self._cache.clear()


class CallerEdits:
    """What the caller edits on a DragPoser method between frames: its settings by name,
    its user constraints and its trackers' weights, each applied from the next frame.

    A base of :class:`engine.methods.dragposer.DragPoserMethod`, which holds the three
    objects edited: the caller's settings, the user's constraints and the trackers' terms.
    """

    _settings: FrameSettings
    _user: UserConstraints
    trackers: TrackerTerms

    @property
    def explicit(self) -> set[str]:
        """Settings fields the caller chose (kept against the sensor-set profiles)."""
        return self._settings.explicit

    @property
    def constraints(self) -> list[Constraint]:
        """The user's constraints, as the solver takes them (captured copies included)."""
        return self._user.items

    def configure(self, **values: Any) -> None:
        """Change settings by name (:meth:`FrameSettings.configure`); from the next frame."""
        self._settings.configure(**values)

    def add_constraint(self, constraint: Constraint) -> None:
        self._user.add(constraint)

    def remove_constraint(self, name: str) -> None:
        self._user.remove(name)

    def get_constraint(self, name: str) -> Constraint:
        return self._user.get(name)

    def set_constraints(self, constraints: Iterable[Constraint]) -> None:
        """Replace all user constraints (names must be unique)."""
        self._user.replace_all(constraints)

    def settle_constraints(self, previous_positions: Any) -> None:
        """Let each constraint capture what it takes from the previous solved pose."""
        self._user.settle(previous_positions)

    def set_weight(self, name: str, weight: float) -> None:
        if not weight >= 0:
            raise UserError(f"constraint {name!r}: weight must be >= 0, got {weight!r}")
        self._user.edit(name, weight=float(weight))

    def set_enabled(self, name: str, enabled: bool) -> None:
        self._user.edit(name, enabled=bool(enabled))

    def set_sensor_weight(self, joint: str, weight: float) -> None:
        """Weight of the tracker on ``joint`` (applies to its ``sensor`` constraint)."""
        self.trackers.set_weight(joint, weight)
