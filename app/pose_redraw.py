"""The pose window's redraw: it listens to its authoring model's events
(:class:`engine.authoring.events.AuthoringEvents`) and redraws what each says changed:
the targets (spheres and the target list), the pose (figure, facing, rotation rings,
constraint gizmos), the key strip, the constraints' panel, the undo and redo entries and
the motion paths. :meth:`PoseRedraw.refresh` shows the whole model; :meth:`PoseRedraw.close`
stops listening.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np

from engine.authoring import events as ev
from engine.authoring.bake import one_key_targets
from engine.authoring.motion_paths import authored_paths
from engine.studio.frame_figures import gizmos_of


class PoseRedraw:
    """The redraw of the pose window ``w`` from its model's events (see the module doc)."""

    def __init__(self, w: Any) -> None:
        self.w = w
        self._subscriptions: list[tuple[Any, Callable]] = []
        for signal, slot in (
            (w.session.events.targets, self._on_targets),
            (w.session.events.frame, self._on_targets),  # a pin's activity is the frame's
            (w.session.events.frame, self._on_frame),  # ... and so is whether its gizmo shows
            (w.session.events.pose, self._on_pose),
            (w.session.events.keys, self._on_keys),
            (w.session.events.animation, self._on_keys),
            (w.session.events.frame, self._on_keys),
            (w.session.events.constraints, self._on_constraints),
            (w.session.events.history, self._on_history),
            (w.session.events.keys, self.paths_due),
            (w.session.events.animation, self.paths_due),
            (w.session.events.bake, self.paths_due),
            (w.session.events.constraints, self.paths_due),  # a pin moves the keys' limbs
            # after the key strip's own update: whether the pose holds an edit not keyed
            (w.session.events.targets, self._on_edited),
            (w.session.events.pose, self._on_edited),
            (w.session.events.keys, self._on_edited),
            (w.session.events.frame, self._on_edited),
            (w.session.events.targets, self._on_key_only),
            (w.session.events.keys, self._on_key_only),
            (w.session.events.frame, self._on_key_only),
            (w.session.events.selection, self._on_selection),
        ):
            signal.connect(slot)
            self._subscriptions.append((signal, slot))

    def close(self) -> None:
        """Stop listening to the model (the window closes)."""
        for signal, slot in self._subscriptions:
            signal.disconnect(slot)
        self._subscriptions.clear()

    def _on_targets(self, e: Any = None) -> None:
        """The target spheres where the solves aim on the frame shown
        (:attr:`engine.authoring.pose_solve.PoseSolving.aimed`: a pin acting there wins
        over its joint's target, as in the bake), and the target list."""
        t = self.w.mode.aimed
        self.w.viewport.sensors.update(
            tuple(t),
            np.array([x.position for x in t.values()]).reshape(-1, 3),
            np.array([x.rotation if x.rotation is not None else [1.0, 0, 0, 0] for x in t.values()]).reshape(-1, 4),
            np.array([x.active for x in t.values()], bool),
            tuple(x.rotation is not None for x in t.values()),
        )
        self.w.targets.set_targets({j: (x.enabled, x.weight, x.rotation is not None) for j, x in t.items()})
        self.w._render_soon()

    def _on_pose(self, e: ev.PoseChanged | None = None) -> None:
        self.w.facing.blockSignals(True)
        self.w.facing.setValue((self.w.mode.heading + 180.0) % 360.0 - 180.0)
        self.w.facing.blockSignals(False)
        self.w.turns.show_handles()
        self._show_gizmos()
        self.w.show_positions(self.w.mode.pose.positions)

    def _on_frame(self, e: Any = None) -> None:
        """Another frame shown: the gizmos of the constraints acting there, even where
        the pose is the same (a frame with no key, before the first bake)."""
        self._show_gizmos()
        self.w._render_soon()

    def _show_gizmos(self) -> None:
        self.show_gizmos(self.w.mode.pose.positions, self.w.frame)

    def show_gizmos(self, positions: np.ndarray, frame: int) -> None:
        """The gizmos of the constraints acting on ``frame`` on the character at
        ``positions (22, 3)`` metres (the pose, or a played frame: a pin's tether runs to
        its joint where it is drawn), as the studio draws them. A constraint outside its
        range and blends on ``frame`` draws nothing: neither seen holding there nor
        taking a press meant for the joint under it (a pin for frames 100-160 would
        otherwise take the press on a wrist left on it at frame 199 and move the pin)."""
        shown = gizmos_of(self.w.mode.constraints, positions, lambda m: self.w.statusBar().showMessage(m, 5000), frame)
        self.w.viewport.gizmos.update(shown)

    def paths_due(self, e: Any = None) -> None:
        """The keys, the animation, the constraints or the bake changed: the paths are
        computed again."""
        s = self.w.session
        self.w.paths.source_changed(
            lambda: authored_paths(
                s.mode.character, s.scene.keys, s.scene.animation.interpolation, s.baked, list(s.scene.constraints)
            )
        )

    def _on_keys(self, e: Any = None) -> None:
        a = self.w.scene.animation
        self.w.keys.set_state(a.frames, a.fps, tuple(k.frame for k in self.w.scene.keys), self.w.frame, a.interpolation)
        self.w.constraints.panel.frames_changed()

    def _on_selection(self, e: ev.SelectionChanged) -> None:
        """Undo or redo gave back another selected joint: its rings, where it is now."""
        self.w.turns.show_handles()
        self.w.paths.select(e.selected)
        self.w._render_soon()

    def _on_key_only(self, e: Any = None) -> None:
        """The targets of one key around an in-between, which do not act on it: the list
        says so, rather than showing no target where a key has one."""
        key_only = one_key_targets(self.w.scene.keys, self.w.frame)
        self.w.targets.set_key_only({j: f for j, f in key_only.items() if j not in self.w.mode.targets})

    def _on_edited(self, e: Any = None) -> None:
        self.w.keys.set_edited(self.w.frame if self.w.session.unkeyed_edit() else None)

    def _on_constraints(self, e: Any = None) -> None:
        self.w.constraints.refresh()
        self._on_targets()  # a pin moved, added or removed moves its joint's target
        self._show_gizmos()
        self.w._render_soon()

    def _on_history(self, e: ev.HistoryChanged) -> None:
        undo, redo = self.w.actions_by_name["undo"], self.w.actions_by_name["redo"]
        undo.setEnabled(e.can_undo)
        undo.setText(f"&Undo {e.undo_text}".rstrip())
        redo.setEnabled(e.can_redo)
        redo.setText(f"&Redo {e.redo_text}".rstrip())

    def refresh(self) -> None:
        """Show the whole model: the pose, its targets, the key strip, the constraints."""
        self._on_targets()
        self._on_keys()
        self._on_edited()
        self._on_key_only()
        self._on_constraints()
        self._on_history(
            ev.HistoryChanged(
                self.w.undo.can_undo(),
                self.w.undo.can_redo(),
                self.w.undo.undo_text(),
                self.w.undo.redo_text(),
                self.w.undo.is_clean(),
                self.w.undo.count(),
            )
        )
        self._on_pose()
