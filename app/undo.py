"""Undo and redo of the studio's scene edits (Ctrl+Z / Ctrl+Shift+Z), on the history the
pose window uses too (:class:`engine.authoring.history.History`).

The history listens to the session's typed events, so every edit is recorded however it
was made (panel, 3D drag, Ctrl-drag pin, scene load) and no widget has to know about
undo. A record holds the sensor set, the constraint list or the optimizer settings set
explicitly, before and after the edit: small tuples and dicts of immutable objects (the
session replaces a constraint object on every edit, never changes it in place), so
undoing is one session call (``set_sensors`` / ``set_constraints`` /
``replace_settings``) that fires its event and reaches the engine like any other edit.
A switch of the reconstruction method or of its ghosts is a step too (``set_method``):
the sensors, constraints and settings are the session's, not the method's, so undoing
the switch brings the previous method back on the scene as it is. A switch the engine
refuses (a method that cannot be built, or cannot run from the sensors) is no step: the
engine's answer names it (:meth:`SceneUndo.refused`) and it leaves the history.

A drag sends an edit per mouse move; consecutive edits of the same thing (one tracker's
offset, one constraint's fields) within :data:`engine.authoring.history.MERGE_S` merge
into one step, and the move of a pin merges into the step that created it. The Edit
menu's actions follow :attr:`SceneUndo.changed` (:func:`undo_actions`).
"""

from __future__ import annotations

import contextlib
from collections.abc import Callable, Iterator
from typing import Any

import numpy as np
from PyQt6.QtCore import QObject, pyqtSignal
from PyQt6.QtGui import QAction

from engine.authoring.history import Edit, History
from widgets.sensor_panel import LABELS


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


class SceneUndo(QObject):
    """Records sensor, constraint, settings and clip edits of ``session`` on :attr:`history`.

    ``changed`` is emitted after every change of the history (an edit, undo, redo, a
    save marking it clean)."""

    changed = pyqtSignal()
    #: The edits were kept (:meth:`set_clean`: a save, a scene loaded, the start set up),
    #: not a history merely cleared for another clip or undone back to a clean state.
    kept = pyqtSignal()

    def __init__(self, session: Any, parent: Any = None) -> None:
        super().__init__(parent)
        self.session = session
        self.history = History(session, self.changed.emit)
        self._sensors = (tuple(session.sensors.values()), session.preset)
        self._constraints = tuple(session.constraints)
        self._settings = dict(session.settings)
        self._method = (session.method, tuple(session.ghosts))
        self._switches: dict[int, Edit] = {}  # recent method switches by their ``opened``
        self._applying = False
        self._same_clip = False
        session.events.sensors.connect(self._on_sensors)
        session.events.constraints.connect(self._on_constraints)
        session.events.settings.connect(self._on_settings)
        session.events.method.connect(self._on_method)
        session.events.motion.connect(self._on_motion)
        session.events.source.connect(self._on_source)

    def close(self) -> None:
        self.session.events.sensors.disconnect(self._on_sensors)
        self.session.events.constraints.disconnect(self._on_constraints)
        self.session.events.settings.disconnect(self._on_settings)
        self.session.events.method.disconnect(self._on_method)
        self.session.events.motion.disconnect(self._on_motion)
        self.session.events.source.disconnect(self._on_source)

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
            self.history.clear()

    def _on_source(self, e: Any) -> None:
        """A tracker recording or live stream replaces the clip: a new history too (the
        edits were offered for saving before it opened)."""
        self.history.clear()

    def record(self, text: str, put: Callable[[Any], None], before: Any, after: Any, key: tuple | None = None) -> None:
        """Record an edit already made: ``put(before)`` undoes it, ``put(after)`` redoes it."""
        self.history.push(Edit(text, before, after, key, put=put))

    def group(self, text: str) -> contextlib.AbstractContextManager[None]:
        """The edits recorded inside are one undo step named ``text``."""
        return self.history.group(text)

    def is_clean(self) -> bool:
        """Whether nothing changed since :meth:`set_clean` (the last save or open)."""
        return self.history.is_clean()

    def set_clean(self) -> None:
        self.history.set_clean()
        self.kept.emit()

    # -- recording ------------------------------------------------------------------
    def _on_sensors(self, e: Any) -> None:
        before, after = self._sensors, (tuple(e.sensors), e.preset)
        self._sensors = after
        if self._applying or not before[0]:  # the first sensor set is the start, not an edit
            return
        key = None
        tracker = f"{LABELS.get(e.joint, e.joint)} tracker"  # the sensor panel's name for it
        if e.joint is not None and e.old is not None and e.new is not None:
            fields = _changed_fields(e.old, e.new)
            key = ("sensor", e.joint, fields)
            if fields == ("offset",):
                text = f"Move {tracker}"
            elif fields == ("enabled",):
                text = f"Turn {'on' if e.new.enabled else 'off'} {tracker}"
            else:
                text = f"Edit {tracker} ({', '.join(fields)})"
        elif e.joint is not None:
            text = f"{'Add' if e.old is None else 'Remove'} {tracker}"
        else:
            text = f"Sensor preset {e.preset}" if e.preset else "Change sensors"
        self.record(text, self._apply_sensors, before, after, key)

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
        self.record(text, self._apply_constraints, before, after, key)

    def _on_settings(self, e: Any) -> None:
        before, after = self._settings, dict(self.session.settings)
        self._settings = after
        if self._applying or before == after:
            return
        names = tuple(sorted(k for k in set(before) | set(after) if before.get(k) != after.get(k)))
        text = f"Set {', '.join(names)}" if len(names) <= 3 else f"Set {len(names)} optimizer settings"
        key = ("setting", names, "value") if len(names) == 1 else None  # a spin box's steps merge
        self.record(text, self._apply_settings, before, after, key)

    def _on_method(self, e: Any) -> None:
        before, after = self._method, (e.method, tuple(e.ghosts))
        self._method = after
        if self._applying or before == after:
            return
        if before[0] != after[0]:
            text = f"Method {after[0]}"
        else:
            text = f"Ghosts {', '.join(after[1])}" if after[1] else "No ghosts"
        edit = Edit(text, before, after, None, put=self._apply_method)
        if before[0] != after[0]:
            # the engine answers a switch later, naming it by this number (a snapshot's
            # ``opened``); ghosts alone are no switch and are never refused
            self._remember_switch(edit)
        self.history.push(edit)

    def _remember_switch(self, edit: Edit) -> None:
        """Name ``edit`` by the switch just sent, so the engine's refusal finds it (the
        last few: the engine answers within a frame or two)."""
        now = self.session.opened
        self._switches = {k: v for k, v in self._switches.items() if k > now - 8}
        self._switches[now] = edit

    def refused(self, opened: int) -> None:
        """The engine kept its method at the switch numbered ``opened`` (``Session.opened``
        when it was sent): that switch changed nothing, so it is no undo step."""
        edit = self._switches.pop(opened, None)
        if edit is not None:
            self.history.discard(edit)

    # -- applying ---------------------------------------------------------------------
    def _apply_method(self, state: tuple) -> None:
        if (self.session.method, tuple(self.session.ghosts)) == state:
            return  # the engine refused the switch: it runs this method already
        with self.unrecorded():
            self.session.set_method(state[0], state[1])
        # an undo or redo the engine refuses is no step either
        edit = next((e for e in self._switches.values() if state is e.before or state is e.after), None)
        if edit is not None:
            self._remember_switch(edit)

    def _apply_settings(self, state: dict) -> None:
        with self.unrecorded():
            self.session.replace_settings(state)

    def _apply_sensors(self, state: tuple) -> None:
        with self.unrecorded():
            self.session.set_sensors(state[0], state[1])

    def _apply_constraints(self, state: tuple) -> None:
        with self.unrecorded():
            self.session.set_constraints(list(state))


def undo_actions(parent: Any, undo: SceneUndo) -> tuple[QAction, QAction]:
    """The Edit menu's Undo and Redo for ``undo``'s history: named after the step they
    undo or redo, disabled when there is none."""
    h = undo.history
    undo_act, redo_act = QAction("&Undo", parent), QAction("&Redo", parent)
    undo_act.triggered.connect(h.undo)
    redo_act.triggered.connect(h.redo)

    def update() -> None:
        undo_act.setEnabled(h.can_undo())
        undo_act.setText(f"&Undo {h.undo_text()}".rstrip())
        redo_act.setEnabled(h.can_redo())
        redo_act.setText(f"&Redo {h.redo_text()}".rstrip())

    undo.changed.connect(update)
    update()
    return undo_act, redo_act
