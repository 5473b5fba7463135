"""The edits a user makes to DragPoser between frames, and the settings a frame runs with.

:class:`DragPoserEdits` is the part of :class:`engine.methods.dragposer.DragPoserMethod`
that the studio and the CLI call between frames (the capabilities
:class:`~engine.methods.base.Configurable`, :class:`~engine.methods.base.Constrainable`
and :class:`~engine.methods.base.SensorWeighted`): optimizer settings by name
(:meth:`~DragPoserEdits.configure`), the user's constraints (:meth:`~DragPoserEdits.add_constraint`,
:meth:`~DragPoserEdits.remove_constraint`, :meth:`~DragPoserEdits.set_constraints`,
:meth:`~DragPoserEdits.set_weight`, :meth:`~DragPoserEdits.set_enabled`) and each
tracker's weight (:meth:`~DragPoserEdits.set_sensor_weight`). Every edit applies from the
next frame. Each frame then runs with the caller's settings completed by the connected
sensor set's profile (:func:`engine.solver.profiles.effective`), for the fields the
caller left alone.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Iterable
from typing import Any

from engine import skeleton as sk
from engine.constraints import Constraint, SensorConstraint
from engine.errors import UserError
from engine.solver import OptimizerSettings
from engine.solver.profiles import effective


class DragPoserEdits:
    """Settings, user constraints and tracker weights of a DragPoser method (a base of
    :class:`~engine.methods.dragposer.DragPoserMethod`, which sets the attributes below).

    Attributes
    ----------
    settings : OptimizerSettings
        The caller's settings; edited in place (callers may hold the object).
    explicit : set of str
        Settings fields the caller chose, kept against the sensor-set profiles.
    constraints : list of Constraint
        The user's constraints, names unique.
    sensor_weights : dict of str to float
        Tracker weight by joint name (1 when absent).
    sensors : dict of str to SensorConstraint
        This clip's tracker terms by joint name.
    """

    settings: OptimizerSettings
    explicit: set[str]
    constraints: list[Constraint]
    sensor_weights: dict[str, float]
    sensors: dict[str, SensorConstraint]
    _effective: dict[tuple, OptimizerSettings]  # per clip: (settings, sensor set) -> settings
    #: id(published constraint) -> (it, the copy that holds what it captured on first use)
    _captured: dict[int, tuple[Constraint, Constraint]]

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

    def add_constraint(self, constraint: Constraint) -> None:
        if any(c.name == constraint.name for c in self.constraints):
            raise UserError(f"a constraint named {constraint.name!r} exists already")
        self.constraints.append(constraint)

    def remove_constraint(self, name: str) -> None:
        self.get_constraint(name)
        self.constraints = [c for c in self.constraints if c.name != name]

    def get_constraint(self, name: str) -> Constraint:
        for c in self.constraints:
            if c.name == name:
                return c
        raise UserError(f"no constraint named {name!r}")

    def set_constraints(self, constraints: Iterable[Constraint]) -> None:
        """Replace all user constraints (names must be unique)."""
        items = list(constraints)
        names = [c.name for c in items]
        if len(set(names)) != len(names):
            raise UserError("constraint names must be unique")
        # a constraint sent again keeps what it captured (a pin's first position)
        kept = {k: v for k, v in self._captured.items() if any(c is v[0] for c in items)}
        self._captured = kept
        self.constraints = [kept[id(c)][1] if id(c) in kept else c for c in items]

    def settle_constraints(self, previous_positions: Any) -> None:
        """Let each constraint capture what it takes from the previous solved pose
        ``(22, 3)`` metres (:meth:`~engine.constraints.base.Constraint.settled`): the copies
        replace them here; the caller's objects are never changed."""
        out = []
        for c in self.constraints:
            s = c.settled(previous_positions)
            if s is not c:
                original = next((v[0] for v in self._captured.values() if v[1] is c), c)
                self._captured[id(original)] = (original, s)
            out.append(s)
        self.constraints = out

    def _replace_constraint(self, name: str, **changes: Any) -> None:
        """An edited copy in place of the named constraint (the caller may hold the old one)."""
        old = self.get_constraint(name)
        self.constraints = [dataclasses.replace(old, **changes) if c is old else c for c in self.constraints]

    def set_weight(self, name: str, weight: float) -> None:
        if not weight >= 0:
            raise UserError(f"constraint {name!r}: weight must be >= 0, got {weight!r}")
        self._replace_constraint(name, weight=float(weight))

    def set_enabled(self, name: str, enabled: bool) -> None:
        self._replace_constraint(name, enabled=bool(enabled))

    def set_sensor_weight(self, joint: str, weight: float) -> None:
        """Weight of the tracker on ``joint`` (applies to its ``sensor`` constraint)."""
        if joint not in sk.JOINT_INDEX:
            raise UserError(f"unknown joint {joint!r}")
        self.sensor_weights[joint] = float(weight)
        if joint in self.sensors:
            self.sensors[joint].weight = float(weight)

    def _effective_settings(self) -> OptimizerSettings:
        """:func:`engine.solver.profiles.effective` for the connected sensors, kept per
        (settings, sensor set): building and validating the settings object every frame
        cost more than the lookup."""
        live = tuple(j for j, c in self.sensors.items() if c.enabled)
        hip = self.sensors.get("root")
        hip_rotation = hip is None or hip.dof == 6
        key = (tuple(vars(self.settings).values()), live, frozenset(self.explicit), hip_rotation)
        s = self._effective.get(key)
        if s is None:
            if len(self._effective) > 64:
                self._effective.clear()
            s = self._effective[key] = effective(self.settings, live, self.explicit, hip_rotation)
        return s
