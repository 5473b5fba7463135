"""The constraint list's event payload, kept free of heavy imports: the studio's and the
pose window's event groups carry it, and the command line reads those modules at start-up."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Literal


@dataclass(frozen=True)
class ConstraintsChanged:
    """The constraint list changed.

    ``action`` is ``added``, ``removed``, ``updated`` (``old`` -> ``new``, same name) or
    ``replaced`` (the whole list, e.g. a scene load; ``old_list`` holds the previous one).
    ``index`` is the position of the added, removed or updated constraint. Constraint
    objects are never modified after they are published: an update replaces the object,
    so ``old`` stays a faithful record of the previous state.
    """

    action: Literal["added", "removed", "updated", "replaced"]
    constraints: tuple[Any, ...]
    name: str = ""
    index: int = -1
    old: Any = None
    new: Any = None
    old_list: tuple[Any, ...] = ()

    @property
    def names(self) -> tuple[str, ...]:
        return tuple(c.name for c in self.constraints)
