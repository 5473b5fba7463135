"""Undo and redo of scene edits (Ctrl+Z / Ctrl+Shift+Z) on a QUndoStack.

The stack listens to the session's typed events, so every edit is recorded however it
was made (panel, 3D drag, Ctrl-drag pin, scene load) and no widget has to know about
undo. A record holds the sensor set, the constraint list or the optimizer settings set
explicitly, before and after the edit: small tuples and dicts of immutable objects (the
session replaces a constraint object on every edit, never changes it in place), so
undoing is one session call (``set_sensors`` / ``set_constraints`` /
``replace_settings``) that fires its event and reaches the engine like any other edit.

A drag sends an edit per mouse move; consecutive edits of the same thing (one tracker's
offset, one constraint's fields) within :data:`MERGE_S` merge into one step, and the
move of a pin merges into the step that created it.
"""

from __future__ import annotations

import contextlib
import time
from collections.abc import Callable, Iterator
from typing import Any

import numpy as np
from PyQt6.QtGui import QUndoCommand, QUndoStack

#: Edits of the same target closer together than this (seconds) are one undo step.
MERGE_S = 0.6
_MERGE_ID = 1201


class StateCommand(QUndoCommand):
    """Switch between two states of a part of the scene with ``apply(state)``.

    ``key`` says what was edited (``("sensor", joint, fields)`` or
    ``("constraint", name, fields)``); None never merges.
    """

    def __init__(
        self, text: str, apply: Callable[[Any], None], before: Any, after: Any, key: tuple | None = None
    ) -> None:
        super().__init__(text)
        self.apply, self.before, self.after, self.key = apply, before, after, key
        self.stamp = time.monotonic()
        self._pushed = False

    def id(self) -> int:
        return _MERGE_ID if self.key is not None else -1

    def mergeWith(self, other: QUndoCommand) -> bool:  # noqa: N802 (Qt's name)
        if not isinstance(other, StateCommand) or other.key is None or self.key is None:
            return False
        same_target = other.key[:2] == self.key[:2]
        fields_ok = other.key[2] == self.key[2] or self.key[2] == "added"
        if not (same_target and fields_ok and other.stamp - self.stamp < MERGE_S):
            return False
        self.after, self.stamp = other.after, other.stamp
        return True

    def redo(self) -> None:
        if self._pushed:  # QUndoStack.push calls redo; the edit has already happened
            self.apply(self.after)
        self._pushed = True

    def undo(self) -> None:
        self.apply(self.before)


def _changed_fields(old: Any, new: Any) -> tuple[str, ...]:
    import dataclasses

    out = []
    for f in dataclasses.fields(old):
        a, b = getattr(old, f.name, None), getattr(new, f.name, None)
        same = (
            np.array_equal(np.asarray(a), np.asarray(b), equal_nan=True)
            if isinstance(a, np.ndarray) or isinstance(b, np.ndarray)
            else a == b
        )
        if not same:
            out.append(f.name)
    return tuple(out)


class SceneUndo:
    """Records sensor and constraint edits of ``session`` on :attr:`stack`."""

    def __init__(self, session: Any, parent: Any = None) -> None:
        self.session = session
        self.stack = QUndoStack(parent)
        self._sensors = (tuple(session.sensors.values()), session.preset)
        self._constraints = tuple(session.constraints)
        self._settings = dict(session.settings)
        self._applying = False
        self._same_clip = False
        session.events.sensors.connect(self._on_sensors)
        session.events.constraints.connect(self._on_constraints)
        session.events.settings.connect(self._on_settings)
        session.events.motion.connect(self._on_motion)

    def close(self) -> None:
        self.session.events.sensors.disconnect(self._on_sensors)
        self.session.events.constraints.disconnect(self._on_constraints)
        self.session.events.settings.disconnect(self._on_settings)
        self.session.events.motion.disconnect(self._on_motion)

    @contextlib.contextmanager
    def unrecorded(self) -> Iterator[None]:
        """Edits made inside are not undo steps (a simulated failure running out)."""
        was, self._applying = self._applying, True
        try:
            yield
        finally:
            self._applying = was

    @contextlib.contextmanager
    def same_clip(self) -> Iterator[None]:
        """A motion set inside is the same clip edited (a range re-solve and its undo):
        the history is kept."""
        was, self._same_clip = self._same_clip, True
        try:
            yield
        finally:
            self._same_clip = was

    @property
    def editing_clip(self) -> bool:
        """Whether the motion being set is the same clip edited (inside :meth:`same_clip`)."""
        return self._same_clip

    def _on_motion(self, e: Any) -> None:
        """A new clip starts a new history (offsets and failures were made for the old one)."""
        if not self.editing_clip:
            self.stack.clear()

    # -- recording ------------------------------------------------------------------
    def _on_sensors(self, e: Any) -> None:
        before, after = self._sensors, (tuple(e.sensors), e.preset)
        self._sensors = after
        if self._applying or not before[0]:  # the first sensor set is the start, not an edit
            return
        key = None
        if e.joint is not None and e.old is not None and e.new is not None:
            fields = _changed_fields(e.old, e.new)
            key = ("sensor", e.joint, fields)
            what = "Move" if fields == ("offset",) else "Edit"
            text = f"{what} {e.joint} sensor" + ("" if what == "Move" else f" ({', '.join(fields)})")
        elif e.joint is not None:
            text = f"{'Add' if e.old is None else 'Remove'} {e.joint} sensor"
        else:
            text = f"Sensor preset {e.preset}" if e.preset else "Change sensors"
        self.stack.push(StateCommand(text, self._apply_sensors, before, after, key))

    def _on_constraints(self, e: Any) -> None:
        before, after = self._constraints, tuple(e.constraints)
        self._constraints = after
        if self._applying:
            return
        key = None
        if e.action == "updated" and e.old is not None and e.new is not None:
            fields = _changed_fields(e.old, e.new)
            key = ("constraint", e.name, fields)
            text = f"Edit {e.name} ({', '.join(fields)})" if fields else f"Edit {e.name}"
        elif e.action == "added":
            key = ("constraint", e.name, "added")
            text = f"Add {e.name}"
        elif e.action == "removed":
            text = f"Remove {e.name}"
        else:
            text = "Replace constraints"
        self.stack.push(StateCommand(text, self._apply_constraints, before, after, key))

    def _on_settings(self, e: Any) -> None:
        before, after = self._settings, dict(self.session.settings)
        self._settings = after
        if self._applying or before == after:
            return
        names = tuple(sorted(k for k in set(before) | set(after) if before.get(k) != after.get(k)))
        text = f"Set {', '.join(names)}" if len(names) <= 3 else f"Set {len(names)} optimizer settings"
        key = ("setting", names, "value") if len(names) == 1 else None  # a spin box's steps merge
        self.stack.push(StateCommand(text, self._apply_settings, before, after, key))

    # -- applying ---------------------------------------------------------------------
    def _apply_settings(self, state: dict) -> None:
        self._applying = True
        try:
            self.session.replace_settings(state)
        finally:
            self._applying = False

    def _apply_sensors(self, state: tuple) -> None:
        self._applying = True
        try:
            self.session.set_sensors(state[0], state[1])
        finally:
            self._applying = False

    def _apply_constraints(self, state: tuple) -> None:
        self._applying = True
        try:
            self.session.set_constraints(list(state))
        finally:
            self._applying = False
