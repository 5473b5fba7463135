"""What changed in the authoring model's constraint list, as one event.

The model edits its list (the one the pose solves and the saved scene share) through
a :class:`engine.editing.constraint_list.ConstraintList` on that list, so names,
checks and replace-never-mutate rules are those of the studio's list. It compares the list
before and after each command (an edit or its undo) and says what changed with
:func:`constraints_event`.
"""

from __future__ import annotations

from engine.constraints.base import Constraint
from engine.editing.events import ConstraintsChanged


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
