"""The settings a DragPoser frame runs with: the caller's, completed by the sensor set's profile.

:class:`FrameSettings` holds the caller's :class:`~engine.solver.OptimizerSettings` (edited
by name with :meth:`~FrameSettings.configure`, applied from the next frame) and which
fields the caller chose; each frame then runs with those completed by the connected
sensor set's profile (:func:`engine.solver.profiles.effective`) for the fields the caller
left alone.
"""

from __future__ import annotations

import dataclasses
from typing import Any

from engine.errors import UserError
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
