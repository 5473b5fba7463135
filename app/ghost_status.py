"""A ghost method that cannot run with the current sensors says so in its own checkbox.

SparsePoser needs the six-tracker preset and RPM head and hands; ticked with another
preset, a ghost fails on every frame. The engine reports such a failure once
(:mod:`engine.studio.thread`); this unticks the ghost, disables its checkbox and puts
the reason in the checkbox's tooltip instead of the status bar, until the sensors
change (when it may run again).
"""

from __future__ import annotations

from typing import Any

from app.shell import StudioShell


class GhostStatus:
    """Watches the drawn snapshots' problems for ghost failures (``window.session``'s
    ghosts, the checkboxes of ``window.optimizer_panel``)."""

    def __init__(self, window: StudioShell) -> None:
        self.w = window
        self.failed: dict[str, str] = {}  # ghost -> why it cannot run
        self._tips: dict[str, str] = {}
        self._seen: set[str] = set()

    def is_ghost_problem(self, message: str) -> bool:
        """Whether ``message`` is a ghost's failure (shown in its row, not the status bar)."""
        return any(message.startswith(f"{g} at frame ") for g in self.w.optimizer_panel.ghost_boxes)

    def on_snapshot(self, snap: Any) -> None:
        session = self.w.session
        for message in snap.recent_errors:
            if message in self._seen:
                continue
            self._seen.add(message)
            ghost = next((g for g in session.ghosts if message.startswith(f"{g} at frame ")), None)
            if ghost is not None:
                self._disable(ghost, message.split(": ", 1)[-1])

    def _disable(self, ghost: str, why: str) -> None:
        self.failed[ghost] = why
        self.w.session.set_ghosts(tuple(g for g in self.w.session.ghosts if g != ghost))
        self.apply()

    def apply(self) -> None:
        """Disable the failed ghosts' checkboxes (again after the panel was refreshed)."""
        for ghost, why in self.failed.items():
            box = self.w.optimizer_panel.ghost_boxes.get(ghost)
            if box is not None:
                self._tips.setdefault(ghost, box.toolTip())
                box.setToolTip(f"{ghost} cannot run with these sensors: {why}")
                box.setEnabled(False)

    def sensors_changed(self, event: Any = None) -> None:
        """Other sensors: every ghost may be tried again (a drag or a weight is not
        another sensor set)."""
        old, new = getattr(event, "old", None), getattr(event, "new", None)
        if old is not None and new is not None and (old.dof, old.enabled) == (new.dof, new.enabled):
            return
        for ghost in list(self.failed):
            box = self.w.optimizer_panel.ghost_boxes.get(ghost)
            if box is not None:
                box.setEnabled(True)
                box.setToolTip(self._tips.pop(ghost, box.toolTip()))
        self.failed.clear()
        self._seen.clear()
