"""Constraints in the pose window: the studio's constraint panel acting on the pose mode.

The panel (:class:`widgets.constraint_panel.ConstraintPanel`, the same schema as the
studio's) adds, edits and removes any user-facing kind (floor, look-at, pin, distance,
bounds...) on :attr:`engine.authoring.pose_mode.PoseMode.constraints`, which every solve
of the pose takes; a new constraint is placed on the pose as it stands
(:func:`app.constraint_placement.placed_params`). The list is also the scene's, so it is
saved with it and the bake's keys and in-betweens honour it. Each edit is one step of the
window's undo stack and solves the pose again.
"""

from __future__ import annotations

from types import SimpleNamespace
from typing import Any

from PyQt6.QtCore import Qt

from app.constraint_placement import placed_params
from app.schema import constraint_schema
from engine.studio.session_constraints import ConstraintEditing
from widgets.constraint_panel import ConstraintPanel


class _ConstraintList(ConstraintEditing):
    """The session's constraint editing (unique names, checked copies) on a plain list:
    nothing to send to an engine and nobody listening."""

    def __init__(self) -> None:
        self.constraints = []
        self.events = SimpleNamespace(constraints=SimpleNamespace(emit=lambda event: None))

    def _send(self, command: Any) -> None:
        return None


class PoseConstraints:
    """The Constraints dock of ``window`` (a :class:`app.pose_window.PoseWindow`)."""

    def __init__(self, window: Any) -> None:
        self.w = window
        self.list = _ConstraintList()
        self.list.constraints = window.mode.constraints
        window.scene.constraints = window.mode.constraints
        self.panel = ConstraintPanel(constraint_schema())
        self.panel.addRequested.connect(self.add)
        self.panel.removeRequested.connect(self.remove)
        self.panel.changed.connect(self.update)
        window._dock("Constraints", self.panel, Qt.DockWidgetArea.RightDockWidgetArea)

    def add(self, kind: str, **params: Any) -> None:
        """Add a ``kind`` constraint placed on the current pose (``params`` override)."""
        spec = self.list.constraint_catalog().get(kind)
        defaults = {} if spec is None else {f.name: f.default for f in spec.fields}
        placed = placed_params(kind, defaults, self.w.mode.pose.positions) | params
        self.w.edit(f"add {kind}", lambda: self.list.add_constraint(kind, **placed), solve=True)

    def remove(self, name: str) -> None:
        self.w.edit(f"remove {name}", lambda: self.list.remove_constraint(name), solve=True)

    def update(self, name: str, changes: dict) -> None:
        self.w.edit(f"edit {name}", lambda: self.list.update_constraint(name, **changes),
                    ("constraint", name, tuple(changes)), solve=True)  # fmt: skip

    # -- undo and display ----------------------------------------------------------
    def state(self) -> tuple:
        return tuple(self.list.constraints)

    def restore(self, state: tuple) -> None:
        """Put the list back (undo); the mode and the scene keep sharing it."""
        self.list.constraints[:] = list(state)

    def refresh(self) -> None:
        self.panel.set_constraints([c.to_dict() for c in self.list.constraints])
