"""The authoring model's constraint list: the studio's constraint editing on a plain list.

:class:`ConstraintList` gives the pose window the same rules as the studio (unique
names, checked copies, objects replaced on every edit, never changed in place) through
:class:`engine.studio.session_constraints.ConstraintEditing`, on the list the pose
solves and the saved scene share. It announces nothing itself: the session compares the
list before and after each command and says what changed (:func:`constraints_event`).
"""

from __future__ import annotations

from types import SimpleNamespace
from typing import Any

from engine.constraints.base import Constraint
from engine.studio.events import ConstraintsChanged
from engine.studio.session_constraints import ConstraintEditing


class ConstraintList(ConstraintEditing):
    """Constraint edits on ``constraints`` (the list is edited in place, so every holder sees them)."""

    def __init__(self, constraints: list[Constraint]) -> None:
        self.constraints = constraints
        self.events = SimpleNamespace(constraints=SimpleNamespace(emit=lambda event: None))

    def _send(self, command: Any) -> None:
        return None  # no engine thread: the session's solves read the list directly


def constraints_event(old: tuple[Constraint, ...], new: tuple[Constraint, ...]) -> ConstraintsChanged:
    """What changed between two constraint lists: one added, removed or updated
    constraint, else the whole list replaced."""
    if len(new) == len(old) + 1:
        for i, c in enumerate(new):
            if i >= len(old) or old[i] is not c:
                if old == new[:i] + new[i + 1 :]:
                    return ConstraintsChanged("added", new, c.name, i, new=c)
                break
    if len(new) == len(old) - 1:
        for i, c in enumerate(old):
            if i >= len(new) or new[i] is not c:
                if new == old[:i] + old[i + 1 :]:
                    return ConstraintsChanged("removed", new, c.name, i, old=c)
                break
    if len(new) == len(old):
        diff = [i for i, (a, b) in enumerate(zip(old, new)) if a is not b]
        if len(diff) == 1:
            i = diff[0]
            return ConstraintsChanged("updated", new, new[i].name, i, old=old[i], new=new[i])
    return ConstraintsChanged("replaced", new, old_list=old)
