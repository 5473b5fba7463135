"""Editing the studio's constraint list: the constraint half of :class:`~engine.studio.session.Session`.

Every edit replaces objects rather than changing them in place (the engine thread and the
undo records hold the old ones), sends the whole new list to the engine and fires one
``constraints`` event that says what changed.
"""

from __future__ import annotations

import dataclasses
from typing import Any

import numpy as np

from engine import skeleton as sk
from engine.constraints.base import Constraint
from engine.errors import UserError
from engine.studio import commands as cmd
from engine.studio import events as ev
from engine.studio.catalog import ConstraintKind, constraint_catalog

#: Prefix of the pin constraints made by :meth:`ConstraintEditing.pin` (one per joint).
PIN_PREFIX = "pin "


class ConstraintEditing:
    """Constraint methods of the session. The class using it provides ``constraints``
    (list of :class:`~engine.constraints.base.Constraint`), ``events`` (with a
    ``constraints`` signal) and ``_send(command)``."""

    constraints: list[Constraint]
    events: Any

    def _send(self, command: Any) -> None:  # pragma: no cover - provided by Session
        raise NotImplementedError

    @staticmethod
    def constraint_catalog() -> dict[str, ConstraintKind]:
        """The kinds users may add, with their fields (:mod:`engine.studio.catalog`)."""
        return constraint_catalog()

    def constraint(self, name: str) -> Constraint:
        for c in self.constraints:
            if c.name == name:
                return c
        raise UserError(f"no constraint named {name!r}")

    def _index(self, name: str) -> int:
        return next((i for i, c in enumerate(self.constraints) if c.name == name), -1)

    def _unique_name(self, base: str) -> str:
        names = {c.name for c in self.constraints}
        if base and base not in names:
            return base
        i = 1
        while f"{base}{i}" in names:
            i += 1
        return f"{base}{i}"

    def add_constraint(self, kind: str, **params: Any) -> str:
        """Add a constraint of a user-facing ``kind`` with ``params`` (others default);
        returns its name (``params["name"]`` made unique, else the kind numbered).

        Raises
        ------
        UserError
            For an unknown or internal kind, an unknown field or a bad value.
        """
        catalog = constraint_catalog()
        if kind not in catalog:
            raise UserError(f"unknown constraint kind {kind!r}; known: {', '.join(catalog)}")
        params = dict(params)
        params["name"] = self._unique_name(str(params.get("name") or kind))
        try:
            constraint = catalog[kind].cls(**params)
        except TypeError as exc:
            raise UserError(f"constraint {kind!r}: {exc}") from exc
        return self.insert_constraint(constraint)

    def insert_constraint(self, constraint: Constraint, index: int | None = None) -> str:
        """Put a constraint object back (undo of a removal) at ``index`` (default: last)."""
        if self._index(constraint.name) >= 0:
            raise UserError(f"a constraint named {constraint.name!r} exists already")
        index = len(self.constraints) if index is None else int(np.clip(index, 0, len(self.constraints)))
        self.constraints.insert(index, constraint)
        self._constraints_changed("added", constraint.name, index, new=constraint)
        return constraint.name

    def remove_constraint(self, name: str) -> None:
        i = self._index(name)
        if i < 0:
            raise UserError(f"no constraint named {name!r}")
        old = self.constraints.pop(i)
        self._constraints_changed("removed", name, i, old=old)

    def update_constraint(self, name: str, **changes: Any) -> None:
        """Set fields (``weight``, ``enabled`` or any parameter) of the named constraint.

        The object is replaced by an edited copy (checked like a new one), never changed
        in place, so the engine thread and undo records keep consistent objects.
        """
        i = self._index(name)
        if i < 0:
            raise UserError(f"no constraint named {name!r}")
        old = self.constraints[i]
        fields = {f.name for f in dataclasses.fields(old) if f.init}
        for key in changes:
            if key not in fields:
                raise UserError(f"constraint {name!r} ({old.kind}) has no field {key!r}")
        if "name" in changes and changes["name"] != name and self._index(changes["name"]) >= 0:
            raise UserError(f"a constraint named {changes['name']!r} exists already")
        try:
            new = dataclasses.replace(old, **changes)
        except (TypeError, ValueError) as exc:
            raise UserError(f"constraint {name!r}: {exc}") from exc
        self.constraints[i] = new
        self._constraints_changed("updated", new.name, i, old=old, new=new)

    def replace_constraint(self, constraint: Constraint) -> None:
        """Put back a whole constraint object under its name (undo of an update)."""
        i = self._index(constraint.name)
        if i < 0:
            raise UserError(f"no constraint named {constraint.name!r}")
        old = self.constraints[i]
        self.constraints[i] = constraint
        self._constraints_changed("updated", constraint.name, i, old=old, new=constraint)

    def set_constraints(self, constraints: list[Constraint]) -> None:
        """Replace the whole list (a scene load, or its undo)."""
        names = [c.name for c in constraints]
        if len(set(names)) != len(names):
            raise UserError("constraint names must be unique")
        old_list = tuple(self.constraints)
        self.constraints = list(constraints)
        self._constraints_changed("replaced", old_list=old_list)

    def pin(self, joint: str, position: np.ndarray) -> str:
        """Pin ``joint`` at ``position`` (metres): the pin constraint of that joint is
        created or moved; returns its name."""
        if joint not in sk.JOINT_INDEX:
            raise UserError(f"unknown joint {joint!r}")
        name = PIN_PREFIX + joint
        position = np.asarray(position, float)
        if self._index(name) >= 0:
            self.update_constraint(name, position=position)
            return name
        return self.add_constraint("pin", name=name, joint=joint, position=position)

    def unpin(self, joint: str) -> None:
        if self._index(PIN_PREFIX + joint) >= 0:
            self.remove_constraint(PIN_PREFIX + joint)

    def _constraints_changed(self, action: str, name: str = "", index: int = -1, **change: Any) -> None:
        constraints = tuple(self.constraints)
        self._send(cmd.SetConstraints(constraints))
        self.events.constraints.emit(ev.ConstraintsChanged(action, constraints, name, index, **change))  # type: ignore[arg-type]
