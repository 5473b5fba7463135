"""A constraint list with its edits: ``session.constraints`` of the studio and the list the
pose window's authoring model edits, a sub-model with its own events.

A :class:`ConstraintList` is a read-only sequence of constraint objects plus the edits
a user makes to it. Every edit replaces objects rather than changing them in place
(the engine thread and the undo records hold the old ones) and fires one
``events.changed`` (:class:`~engine.editing.events.ConstraintsChanged`) that says what
changed. It knows nothing of engines: the :class:`~engine.studio.session.Session` that
owns it subscribes, sends the new list to its engine and re-emits the event as
``session.events.constraints``.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence
from typing import Any, overload

import numpy as np
from psygnal import Signal, SignalGroup

from engine import skeleton as sk
from engine.constraints.base import Constraint
from engine.editing.catalog import ConstraintKind, constraint_catalog
from engine.editing.events import ConstraintsChanged
from engine.errors import UserError

#: Prefix of the pin constraints made by :meth:`ConstraintList.pin` (one per joint).
PIN_PREFIX = "pin "


class ConstraintListEvents(SignalGroup):
    """``changed``: one :class:`~engine.editing.events.ConstraintsChanged` per edit."""

    changed = Signal(ConstraintsChanged)


class ConstraintList(Sequence[Constraint]):
    """User constraints, in order, with the edits a user makes; see the module doc.

    Parameters
    ----------
    items : list of Constraint, optional
        A list to edit in place (one its owner shares with others, as the pose window's
        is with its pose mode and scene); a new empty one by default.

    Attributes
    ----------
    events : ConstraintListEvents
        ``events.changed`` fires after every edit.
    """

    def __init__(self, items: list[Constraint] | None = None) -> None:
        self._items: list[Constraint] = [] if items is None else items
        self.events = ConstraintListEvents()

    # -- reading ---------------------------------------------------------------------
    @overload
    def __getitem__(self, index: int) -> Constraint: ...
    @overload
    def __getitem__(self, index: slice) -> Sequence[Constraint]: ...
    def __getitem__(self, index: int | slice) -> Constraint | Sequence[Constraint]:
        return self._items[index]

    def __len__(self) -> int:
        return len(self._items)

    def __repr__(self) -> str:
        return f"ConstraintList({', '.join(self.names)})"

    @property
    def names(self) -> tuple[str, ...]:
        return tuple(c.name for c in self._items)

    @staticmethod
    def catalog() -> dict[str, ConstraintKind]:
        """The kinds users may add, with their fields (:mod:`engine.editing.catalog`)."""
        return constraint_catalog()

    def named(self, name: str) -> Constraint:
        """The constraint called ``name``; :class:`UserError` when there is none."""
        i = self.position(name)
        if i < 0:
            raise UserError(f"no constraint named {name!r}")
        return self._items[i]

    def position(self, name: str) -> int:
        """Index of the constraint called ``name``, -1 when there is none."""
        return next((i for i, c in enumerate(self._items) if c.name == name), -1)

    def unique_name(self, base: str) -> str:
        """``base``, or ``base`` numbered (``pin1``, ``pin2``...) when it is taken."""
        names = set(self.names)
        if base and base not in names:
            return base
        i = 1
        while f"{base}{i}" in names:
            i += 1
        return f"{base}{i}"

    # -- editing ---------------------------------------------------------------------
    def add(self, kind: str, **params: Any) -> str:
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
        params["name"] = self.unique_name(str(params.get("name") or kind))
        try:
            constraint = catalog[kind].cls(**params)
        except TypeError as exc:
            raise UserError(f"constraint {kind!r}: {exc}") from exc
        return self.insert(constraint)

    def insert(self, constraint: Constraint, index: int | None = None) -> str:
        """Put a constraint object in at ``index`` (default: last; an undo of a removal)."""
        if self.position(constraint.name) >= 0:
            raise UserError(f"a constraint named {constraint.name!r} exists already")
        index = len(self._items) if index is None else int(np.clip(index, 0, len(self._items)))
        self._items.insert(index, constraint)
        self._changed("added", constraint.name, index, new=constraint)
        return constraint.name

    def remove(self, name: str) -> None:
        i = self.position(name)
        if i < 0:
            raise UserError(f"no constraint named {name!r}")
        old = self._items.pop(i)
        self._changed("removed", name, i, old=old)

    def edit(self, name: str, **changes: Any) -> None:
        """Set fields (``weight``, ``enabled`` or any parameter) of the named constraint.

        The object is replaced by an edited copy (checked like a new one), never changed
        in place, so the engine thread and undo records keep consistent objects.
        """
        old = self.named(name)
        fields = {f.name for f in dataclasses.fields(old) if f.init}
        for key in changes:
            if key not in fields:
                raise UserError(f"constraint {name!r} ({old.kind}) has no field {key!r}")
        if "name" in changes and changes["name"] != name and self.position(changes["name"]) >= 0:
            raise UserError(f"a constraint named {changes['name']!r} exists already")
        try:
            new = dataclasses.replace(old, **changes)
        except (TypeError, ValueError) as exc:
            raise UserError(f"constraint {name!r}: {exc}") from exc
        i = self.position(name)
        self._items[i] = new
        self._changed("updated", new.name, i, old=old, new=new)

    def replace(self, constraint: Constraint) -> None:
        """Put back a whole constraint object under its name (undo of an edit)."""
        old = self.named(constraint.name)
        i = self.position(constraint.name)
        self._items[i] = constraint
        self._changed("updated", constraint.name, i, old=old, new=constraint)

    def set_all(self, constraints: Sequence[Constraint]) -> None:
        """Replace the whole list (a scene load, or its undo)."""
        names = [c.name for c in constraints]
        if len(set(names)) != len(names):
            raise UserError("constraint names must be unique")
        old_list = tuple(self._items)
        self._items[:] = list(constraints)
        self._changed("replaced", old_list=old_list)

    def pin(self, joint: str, position: np.ndarray) -> str:
        """Pin ``joint`` at ``position`` (metres): the pin constraint of that joint is
        created or moved; returns its name."""
        if joint not in sk.JOINT_INDEX:
            raise UserError(f"unknown joint {joint!r}")
        name = PIN_PREFIX + joint
        position = np.asarray(position, float)
        if self.position(name) >= 0:
            self.edit(name, position=position)
            return name
        return self.add("pin", name=name, joint=joint, position=position)

    def unpin(self, joint: str) -> None:
        if self.position(PIN_PREFIX + joint) >= 0:
            self.remove(PIN_PREFIX + joint)

    def _changed(self, action: str, name: str = "", index: int = -1, **change: Any) -> None:
        event = ConstraintsChanged(action, tuple(self._items), name, index, **change)  # type: ignore[arg-type]
        self.events.changed.emit(event)
