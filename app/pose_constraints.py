"""Constraints in the pose window: the studio's constraint panel acting on the authoring model.

The panel (:class:`widgets.constraint_panel.ConstraintPanel`, the same schema as the
studio's) adds, edits and removes any user-facing kind (floor, look-at, pin, distance,
bounds...) through the model
(:meth:`engine.authoring.session.AuthoringSession.add_constraint` and its siblings), whose
list every solve of the pose takes and the scene saves, so the bake's keys and
in-betweens honour it. A new constraint is placed on the pose as it stands
(:func:`app.constraint_placement.placed_params`). Each edit is one undo step of the
model and solves the pose again; the panel redraws on the model's ``constraints`` event.
"""

from __future__ import annotations

from typing import Any

from PyQt6.QtCore import Qt

from app.constraint_placement import moved_params, placed_params
from app.constraint_ranges import link_ranges
from app.schema import constraint_schema
from widgets.constraint_panel import ConstraintPanel


class PoseConstraints:
    """The Constraints dock of ``window`` (a :class:`app.pose_window.PoseWindow`)."""

    def __init__(self, window: Any) -> None:
        self.w = window
        self.panel = ConstraintPanel(
            constraint_schema(),
            empty_hint="No constraints yet: pick a kind above (floor, look-at, pin, distance...) and "
            "press Add; it is placed where the body stands and every solve of the pose honours it.",
        )
        self.panel.addRequested.connect(self.add)
        self.panel.removeRequested.connect(self.remove)
        self.panel.changed.connect(self.update)
        # the key strip is built after this dock: looked up when a span is drawn
        link_ranges(
            self.panel,
            lambda span: window.keys.set_constraint_span(span),
            lambda: window.frame,
            lambda: window.scene.animation.frames,
        )
        self.dock = window._dock("Constraints", self.panel, Qt.DockWidgetArea.RightDockWidgetArea)

    def add(self, kind: str, **params: Any) -> None:
        """Add a ``kind`` constraint placed on the current pose (``params`` override); one
        on a single joint goes on the selected joint, or on one no ``kind`` constraint holds."""
        session = self.w.session
        spec = session.constraint_catalog().get(kind)
        defaults = {} if spec is None else {f.name: f.default for f in spec.fields}
        taken = {j for c in session.mode.constraints if c.kind == kind for j in c.acts_on()}
        placed = placed_params(kind, defaults | params, session.pose.positions, self.w.selected, taken) | params
        self.w._edit(lambda: session.add_constraint(kind, **placed))

    def remove(self, name: str) -> None:
        self.w._edit(lambda: self.w.session.remove_constraint(name))

    def update(self, name: str, changes: dict) -> None:
        """Edit the constraint ``name``; one put on other joints is placed on them
        (:func:`app.constraint_placement.moved_params`)."""
        session = self.w.session
        current = next((c for c in session.mode.constraints if c.name == name), None)
        if current is not None:
            changes = moved_params(current, changes, session.pose.positions)
        self.w._edit(lambda: session.update_constraint(name, changes))

    def refresh(self) -> None:
        self.panel.set_constraints([c.to_dict() for c in self.w.session.mode.constraints])
