"""The studio's latent-debugging views and their wiring (docs/latent.md, "In the studio").

A "Latent map" dock, tabbed beside the Latent dock, holds three tabs: *Map* (the latent
map over the prior readouts), *Forces* (term forces of the frame on screen) and
*Gallery* (the dimension sweep). The map and the readouts read one store of every
frame solved since the clip or method was opened
(:class:`engine.latent.solved_frames.SolvedFrames`): a seek that restarts the engine's
history keeps the trajectory, and another clip or method empties it, ignoring the
snapshots of what was open before (``Snapshot.opened``). Requests go to the session: a click on a trajectory
point seeks its frame; a click elsewhere pauses and decodes the point as the white debug
pose; hovering decodes too while paused; *Inspect this frame* asks the engine for the
forces and the sweep; *Next flagged frame* seeks. Flagged frames are marked on the
timeline. The panels are drawn from snapshots by the window's draw scheduler, only
while their tab is visible, and again from the newest snapshot when a tab comes into view
(a paused engine sends no other). Whether the dock or the Latent dock was in front is kept in
the window's settings (``latent_map_raised``) for the next start.

The tabs are built when the dock is first shown: behind the Latent dock (where it starts)
the map, forces and gallery cost the window ~0.2 s of CPU at start-up and draw nothing.
The readouts are built at once, hidden: their flag verdicts mark the timeline meanwhile.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from PyQt6.QtCore import Qt, QTimer
from PyQt6.QtWidgets import QDockWidget, QSplitter, QTabWidget, QWidget

from app.drawing import Panel
from app.shell import StudioShell
from engine.latent.projection import default_map
from engine.latent.solved_frames import SolvedFrames
from engine.studio import events as ev
from widgets.latent_forces import LatentForces
from widgets.latent_gallery import LatentGallery
from widgets.latent_map import LatentMapPlot
from widgets.latent_readouts import LatentReadouts

#: Hover decodes are sent at most this often, ms (a mouse sends ~100 moves a second).
HOVER_MS = 40
#: A view brought to the front is drawn once it is on screen: looked for this many times,
#: this many ms apart.
REDRAW_TRIES, REDRAW_RETRY_MS = 10, 50
#: The settings key that remembers the dock in front of the Latent dock.
RAISED = "latent_map_raised"
NO_MAP = "No latent map: assets/models/latent_map.npz is missing or belongs to another VAE."


def _on_screen(widget: Any) -> bool:
    """Whether any of ``widget`` is on screen: a dock tabified behind another stays
    ``isVisible()`` (moved out of the window), but shows nothing."""
    return widget.isVisible() and not widget.visibleRegion().isEmpty()


class LatentViews:
    """Builds the dock on ``window`` (the main window) and connects it; see the module doc."""

    def __init__(self, window: StudioShell) -> None:
        self.w = window
        self.session = window.session
        self._redraw_timer = QTimer(window, singleShot=True)  # owned: it dies with the window
        self._redraw_timer.timeout.connect(self._redraw)
        self._redraw_left = 0
        self.latent_map = default_map()
        self.solved = SolvedFrames()
        self.readouts = LatentReadouts(solved=self.solved)
        if self.latent_map is not None:
            self.readouts.set_thresholds(self.latent_map.nn_threshold, self.latent_map.norm_threshold)
        #: Built with the tabs when the dock is first shown (:meth:`build`); None until then.
        self.map: LatentMapPlot | None = None
        self.forces: LatentForces | None = None
        self.gallery: LatentGallery | None = None
        self.tabs: QTabWidget | None = None
        self._detail: Any = None  # the newest snapshot's latent detail, for tabs built later
        self.dock = QDockWidget("Latent map", window)
        self.dock.setObjectName("Latent map")
        self.dock.setWidget(QWidget())
        self.dock.visibilityChanged.connect(self._dock_shown)
        window.addDockWidget(Qt.DockWidgetArea.RightDockWidgetArea, self.dock)
        latent = window.findChild(QDockWidget, "Latent")
        if latent is not None:
            window.tabifyDockWidget(latent, self.dock)
            in_front = self.dock if window.settings.value(RAISED, False, type=bool) else latent
            in_front.raise_()
        window.tabifiedDockWidgetActivated.connect(
            lambda dock: (
                window.settings.setValue(RAISED, dock is self.dock)
                if dock.objectName() in ("Latent", "Latent map")
                else None
            )
        )
        self._hover: tuple[str, Any] | None = None
        self._hover_timer = QTimer(window, singleShot=True, interval=HOVER_MS)
        self._hover_timer.timeout.connect(self._send_hover)
        self.readouts.seekRequested.connect(self.seek)
        self.readouts.flagsChanged.connect(window.timeline.set_marks)
        window.session.events.motion.connect(self._forget)
        window.session.events.source.connect(self._forget)  # a recording or live stream: another clip
        window.session.events.method.connect(self._forget)
        window.drawing.panels += [
            Panel("latent map", self._update_map, 0.5),
            Panel("latent detail", self._update_detail, 0.5),
        ]

    def close(self) -> None:
        """Close the dock's views while their plots exist (the window's close calls this):
        each takes its items out of its plots (:func:`widgets.plots.release`)."""
        self._redraw_timer.stop()
        self._hover_timer.stop()
        e = self.session.events
        for signal in (e.motion, e.source, e.method):
            signal.disconnect(self._forget)
        for view in (self.readouts, self.map, self.forces, self.gallery):
            if view is not None:
                view.close()

    def build(self) -> None:
        """The dock's tabs (Map with the readouts under it, Forces, Gallery), once."""
        if self.tabs is not None:
            return
        self.map = LatentMapPlot(solved=self.solved)
        self.forces = LatentForces(self.w.plots.colours)
        self.gallery = LatentGallery()
        if self.latent_map is not None:
            m = self.latent_map
            self.map.set_map(m.density, m.extent, m.explained)
        else:
            self.map.set_note(NO_MAP)
        split = QSplitter(Qt.Orientation.Vertical)
        split.addWidget(self.map)
        split.addWidget(self.readouts)
        split.setSizes([300, 150])
        self.tabs = QTabWidget()
        self.tabs.addTab(split, "Map")
        self.tabs.addTab(self.forces, "Forces")
        self.tabs.addTab(self.gallery, "Gallery")
        self.dock.setWidget(self.tabs)
        self.tabs.currentChanged.connect(lambda _: self._redraw_soon())
        self.map.frameClicked.connect(self.seek)
        self.map.pointClicked.connect(self._click_point)
        self.map.pointHovered.connect(lambda x, y: self._queue_hover(("point", (x, y))))
        self.map.frameHovered.connect(lambda f: self._queue_hover(("frame", f)))
        self.forces.inspectRequested.connect(self.inspect)
        self.forces.iteration.valueChanged.connect(lambda _: self._draw_forces())
        if self._detail is not None:
            self.forces.set_detail(self._detail)
            self.gallery.set_detail(self._detail)
            self._draw_forces()

    def _dock_shown(self, shown: bool) -> None:
        if shown:
            self.build()
            self._redraw_soon()

    def _redraw_soon(self) -> None:
        """Draw the newest snapshot once the tab or dock now in front is laid out: the
        draw scheduler hands each snapshot over once, and a hidden tab skipped it."""
        self._redraw_left = REDRAW_TRIES
        self._redraw_timer.start(0)

    def _redraw(self) -> None:
        snap = self.session.latest
        if snap is None:
            return
        if self.map is not None and not _on_screen(self.map) and not _on_screen(self.forces) and self._redraw_left:
            # the dock or tab brought to the front is laid out in a later pass (later still
            # on a busy machine): look again shortly
            self._redraw_left -= 1
            self._redraw_timer.start(REDRAW_RETRY_MS)
            return
        if self.map is not None:
            self.map.mark_stale()
        self.readouts.mark_stale()
        self._update_map(snap)
        self._update_detail(snap)

    # -- snapshots -> views ------------------------------------------------------------
    def _update_map(self, snap: Any) -> None:
        """The map and the readouts while they are in view; the flag verdicts always (they
        mark the timeline)."""
        if snap.opened != self.session.opened:  # of the clip or method before
            return
        if self.map is not None and _on_screen(self.map):
            self.map.update_snapshot(snap)
            self._draw_blend()
        if _on_screen(self.readouts):
            self.readouts.update_snapshot(snap)
        else:
            self.readouts.note_verdicts(snap)

    def _update_detail(self, snap: Any) -> None:
        if snap.opened != self.session.opened:
            return
        d = snap.latent_detail
        self._detail = d
        if self.forces is None or self.gallery is None:
            return
        changed = d is not self.forces.detail
        # no detail: the tab says why (not inspected yet, or a method without a latent)
        self.forces.set_detail(d, str(snap.latent_note))
        self.gallery.set_detail(d)
        if changed:
            self._draw_forces()

    def _draw_blend(self) -> None:
        """The Latent panel's stored A and B (its A to B blend) on the map."""
        if self.map is None:
            return
        stored = self.w.latent.stored
        a, b = stored.get("a"), stored.get("b")
        m = self.latent_map
        ok = m is not None and a is not None and b is not None and a.size == b.size == m.latent_dim
        self.map.set_blend(m.project(a) if ok else None, m.project(b) if ok else None)

    def _draw_forces(self) -> None:
        """The inspected frame's term forces on the map, from its path at the iteration the
        Forces tab shows."""
        if self.forces is None or self.map is None:
            return
        d, snap = self.forces.detail, self.session.latest
        view = None if snap is None else snap.latent_view
        if d is None or view is None or view.frame != d.frame or view.path_xy is None:
            self.map.set_forces(None)
            return
        k = min(self.forces.iteration.value(), len(d.plane) - 1, len(view.path_xy) - 1)
        self.map.set_forces(view.path_xy[k], d.plane[k], [self.forces.colour(n) for n in d.names])

    def _forget(self, event: Any = None) -> None:
        """Another clip or method: empty every view until its first solve arrives (other
        ghosts change no latent)."""
        if isinstance(event, ev.MethodChanged) and event.method == event.old_method:
            return
        self.readouts.clear()
        self._detail = None
        if self.map is not None:
            self.map.clear()
        if self.forces is not None and self.gallery is not None:
            self.forces.set_detail(None)
            self.gallery.set_detail(None)

    # -- requests ------------------------------------------------------------------------
    def seek(self, frame: int) -> None:
        self.session.pause()
        self.session.seek(int(frame))

    def inspect(self, joint: str) -> None:
        self.session.pause()
        self.session.inspect_latent(joint)

    def latent_of_point(self, x: float, y: float) -> np.ndarray | None:
        """The latent the map point ``(x, y)`` stands for: the frame on screen's latent moved
        within the map plane (:meth:`engine.latent.projection.LatentMap.move_to`)."""
        snap = self.session.latest
        if self.latent_map is None or snap is None or snap.latent_view is None:
            return None
        return self.latent_map.move_to(snap.latent_view.latent, np.array([x, y]))

    def latent_of_frame(self, frame: int) -> np.ndarray | None:
        snap = self.session.latest
        if snap is None:
            return None
        return next(
            (np.asarray(r.latent, float) for r in snap.history if r.frame == frame and r.latent is not None), None
        )

    def _click_point(self, x: float, y: float) -> None:
        z = self.latent_of_point(x, y)
        if z is not None:
            self.session.pause()
            self.session.decode_latent(z)

    def _queue_hover(self, what: tuple[str, Any]) -> None:
        if self.session.playing:  # decoding pauses the engine: hovering only points while playing
            return
        self._hover = what
        if not self._hover_timer.isActive():
            self._hover_timer.start()

    def _send_hover(self) -> None:
        if self._hover is None or self.session.playing:
            return
        kind, value = self._hover
        self._hover = None
        z = self.latent_of_point(*value) if kind == "point" else self.latent_of_frame(value)
        if z is not None:
            self.session.decode_latent(z)
