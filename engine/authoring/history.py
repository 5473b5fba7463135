"""The undo history of the studio and the pose window: edits as commands on a stack,
merged while a drag goes on.

A command has ``text`` (what the Edit menu says), ``apply(session)`` and
``undo(session)`` and may merge a later command into itself (:meth:`Edit.merge`). The
:class:`History` keeps them in order with an index (commands before it are done) and a
clean index (where the scene was last saved), and reports every change through
``on_change``, which the session turns into a ``history`` event.

Consecutive edits of the same thing (one target's position, one constraint's fields)
less than :data:`MERGE_S` apart are one step, so a drag of a hundred mouse moves undoes
in one Ctrl+Z; an edit keyed ``(kind, name, "added")`` takes the next edits of the same
thing into it. Edits pushed inside :meth:`History.group` are one step (loading a scene
replaces the sensors, the constraints and the settings: one Ctrl+Z puts all back).

The pose window's model (:class:`engine.authoring.session.AuthoringSession`) records
:class:`Edit` s of its whole state; the studio (``app.undo``) records edits of one part
each (the sensors, the constraints, the settings, the clip), given the function that
puts that part back (``Edit.put``).
"""

from __future__ import annotations

import contextlib
import time
from collections.abc import Callable, Iterator
from dataclasses import dataclass, field
from typing import Any, Protocol

#: Edits of the same thing closer together than this (seconds) are one undo step.
MERGE_S = 0.6


class Command(Protocol):
    """One undoable step of the authoring model."""

    text: str

    def apply(self, session: Any) -> None:
        """Make the change (again) on ``session``."""

    def undo(self, session: Any) -> None:
        """Put ``session`` back as it was before the change."""

    def merge(self, other: Command) -> bool:
        """Take ``other`` (the next step) into this one; whether it did."""


@dataclass
class Edit:
    """An edit: the parts of the model it touched before and after
    (:class:`engine.authoring.state.AuthoringState`).

    ``key`` says what was edited, ``(kind, name, fields)`` such as
    ``("target", "lwrist", "position")``; None never merges. ``stamp``: seconds on the
    history's clock when it was made; ``began``: when its work began (None: at ``stamp``).
    An edit merges into the last one when the pause between them, from the last one's
    ``stamp`` to this one's ``began``, is under :data:`MERGE_S`: a drag whose solves take
    longer than that on a loaded machine is still one step. ``put(state)`` makes ``state``
    the model's; None: ``session.restore_state(state)``.
    """

    text: str
    before: Any
    after: Any
    key: tuple | None = None
    stamp: float = field(default_factory=time.monotonic)
    put: Callable[[Any], None] | None = None
    began: float | None = None

    def _put(self, session: Any, state: Any) -> None:
        if self.put is None:
            session.restore_state(state)
        else:
            self.put(state)

    def apply(self, session: Any) -> None:
        self._put(session, self.after)

    def undo(self, session: Any) -> None:
        self._put(session, self.before)

    def merge(self, other: Command) -> bool:
        if not isinstance(other, Edit) or other.key is None or self.key is None:
            return False
        same = other.key[:2] == self.key[:2] and (other.key[2] == self.key[2] or self.key[2] == "added")
        began = other.stamp if other.began is None else other.began
        if not (same and began - self.stamp < MERGE_S):
            return False
        self.after, self.stamp = other.after, other.stamp
        return True


@dataclass
class Group:
    """Several commands as one step: applied in order, undone in reverse; never merges."""

    text: str
    commands: list[Command] = field(default_factory=list)

    def apply(self, session: Any) -> None:
        for c in self.commands:
            c.apply(session)

    def undo(self, session: Any) -> None:
        for c in reversed(self.commands):
            c.undo(session)

    def merge(self, other: Command) -> bool:
        return False


class History:
    """Undo and redo of ``session``'s commands (see the module doc).

    Parameters
    ----------
    session : object
        What the commands apply to.
    on_change : callable, optional
        Called with no arguments after every change of the history.
    """

    def __init__(self, session: Any, on_change: Callable[[], None] | None = None) -> None:
        self.session = session
        self.on_change = on_change or (lambda: None)
        self._commands: list[Command] = []
        self._index = 0
        self._clean: int | None = 0  # None: the saved state can no longer be reached
        self._group: Group | None = None

    @contextlib.contextmanager
    def group(self, text: str) -> Iterator[None]:
        """The commands pushed inside are one step named ``text`` (none when none was
        pushed); nested groups join the outer one."""
        if self._group is not None:
            yield
            return
        self._group = Group(text)
        try:
            yield
        finally:
            g, self._group = self._group, None
            if g.commands:
                self.push(g)

    def push(self, command: Command) -> None:
        """Record ``command``, already applied (merged into the last step when it can be,
        unless that step is where the scene was saved); steps undone before are dropped."""
        if self._group is not None:
            top = self._group.commands[-1] if self._group.commands else None
            if top is None or not top.merge(command):
                self._group.commands.append(command)
            return
        del self._commands[self._index :]
        if self._clean is not None and self._clean > self._index:
            self._clean = None
        top = self._commands[-1] if self._commands else None
        if top is not None and self._clean != self._index and top.merge(command):
            self.on_change()
            return
        self._commands.append(command)
        self._index += 1
        self.on_change()

    def undo(self) -> None:
        """Undo the last step done (nothing when there is none)."""
        if self._index == 0:
            return
        self._index -= 1
        self._commands[self._index].undo(self.session)
        self.on_change()

    def redo(self) -> None:
        """Redo the next step undone (nothing when there is none)."""
        if self._index == len(self._commands):
            return
        self._commands[self._index].apply(self.session)
        self._index += 1
        self.on_change()

    def discard(self, command: Command) -> bool:
        """Forget ``command``, a step whose change did not happen (a method switch the
        engine refused), wherever it is in the history or in a group of it; whether it
        was there. The other steps stay as they are, in order; a group left empty goes."""
        for i, c in enumerate(self._commands):
            if isinstance(c, Group) and any(sub is command for sub in c.commands):
                c.commands = [sub for sub in c.commands if sub is not command]
                if c.commands:
                    self.on_change()
                    return True
            elif c is not command:
                continue
            del self._commands[i]
            if i < self._index:
                self._index -= 1
            if self._clean is not None and self._clean > i:
                self._clean -= 1  # the step changed nothing: the saved state is one step nearer
            self.on_change()
            return True
        return False

    def count(self) -> int:
        """Steps recorded (done and undone)."""
        return len(self._commands)

    def texts(self) -> list[str]:
        """The names of the recorded steps, oldest first (done and undone)."""
        return [c.text for c in self._commands]

    def can_undo(self) -> bool:
        return self._index > 0

    def can_redo(self) -> bool:
        return self._index < len(self._commands)

    def undo_text(self) -> str:
        return self._commands[self._index - 1].text if self._index > 0 else ""

    def redo_text(self) -> str:
        return self._commands[self._index].text if self._index < len(self._commands) else ""

    def is_clean(self) -> bool:
        """Whether the model is as it was when :meth:`set_clean` was last called."""
        return self._clean == self._index

    def set_clean(self) -> None:
        """Mark the present state as saved."""
        self._clean = self._index
        self.on_change()

    def clear(self) -> None:
        """Forget every step (a new document); the present state is clean."""
        self._commands.clear()
        self._index, self._clean = 0, 0
        self.on_change()
