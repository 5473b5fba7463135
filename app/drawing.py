"""What each display tick of the studio draws: the 3D view first, then one panel.

The engine publishes snapshots at its own pace; a QTimer calls :meth:`DrawScheduler.tick`
about 60 times a second. A tick draws the newest snapshot in the 3D view when there is
one, then updates at most one *panel* that is due (timeline, the three plots, the
latent view, the status bar), each at a rate it can afford while playing (plots a few
times a second; a label repaint under software rendering can cost more than the whole
3D view). No tick does everything, so the event loop is never blocked for long and the
view never waits for the panels. Every update's cost is recorded per panel
(:meth:`DrawScheduler.costs`) for ``gui --measure``.
"""

from __future__ import annotations

import time
from collections import deque
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from PyQt6.QtCore import QTimer

from app.engine_watch import EngineWatch
from app.shell import StudioShell
from engine.startup_trace import mark

#: The display tick, ms: how soon a new snapshot is drawn (the tick itself costs ~0.1 ms).
TICK_MS = 8
#: After a view draw costing c ms the next one waits REST x c: at most ~80 % of the GUI
#: thread goes to the 3D view when snapshots come faster than it can draw them, so
#: input and the panels still get their turn.
VIEW_REST = 0.25
#: After the view, a panel is updated in the same tick only when the tick has spent less
#: than this, ms (otherwise in a later tick, unless overdue by a whole interval).
PANEL_BUDGET_MS = 12.0


@dataclass
class Panel:
    """One widget refreshed from snapshots: ``update(snap)`` at most every
    ``interval_s`` while playing (at once when paused)."""

    name: str
    update: Callable[[Any], None]
    interval_s: float
    seq: int = -1
    at: float = 0.0
    costs: deque = field(default_factory=lambda: deque(maxlen=2000))


class DrawScheduler:
    """Drives the window's drawing; see the module doc. ``window`` is the main window."""

    def __init__(self, window: StudioShell) -> None:
        self.w = window
        self.interval_ms = TICK_MS
        self.view_costs: deque = deque(maxlen=2000)
        self.draws = 0  # view draws since start (``gui --measure`` reads it)
        self._drawn_seq = -1
        # a refused method switch is said by one snapshot, which a newer one can replace in
        # ``session.latest`` before a tick reads it: the engine's listeners (every snapshot,
        # on its own thread) keep it here until the tick acts on it, once
        self._refusal: Any = None
        self._refused_seq = -1
        self._listened: Any = None  # the engine whose listeners hold :meth:`_note_refusal`
        self._rate_draws, self._draw_rate, self._rate_t0 = 0, 0.0, time.monotonic()
        self._next_view_at = 0.0  # perf_counter() time before which the view rests
        self._status_text: dict[str, str] = {}
        self.engine_watch = EngineWatch(window)
        w = window
        self.panels = [
            # while playing: a plot's repaint (Qt paints it after the update) costs
            # 10-25 ms on software rendering, so each plot changes once or twice a second
            Panel("timeline", self._follow_playback, 0.1),
            Panel("plot:iterations", w.plots.update_iterations, 0.5),
            Panel("plot:cost", w.plots.update_cost, 1.0),
            Panel("plot:history", w.plots.update_history, 1.0),
            Panel("latent", w.latent.update_snapshot, 0.5),
            Panel("plot:methods", w.method_errors.update_snapshot, 0.25),  # samples the errors
            Panel("status", self._update_status, 0.5),
        ]

    @property
    def draw_rate(self) -> float:
        """View draws per second over the last whole second."""
        return self._draw_rate

    def tick(self) -> None:
        t0 = time.perf_counter()
        now = time.monotonic()
        if now - self._rate_t0 >= 1.0:
            self._draw_rate, self._rate_draws, self._rate_t0 = self._rate_draws / (now - self._rate_t0), 0, now
        self.engine_watch.check()  # a dead solver process: restarted, or why not
        self._listen()
        snap = self.w.session.latest
        if snap is None:
            return
        self._mirror_engine(snap)
        if snap.opened < self.w.session.clip_opened:
            # solved on the clip or source open before (a solve in flight when it was
            # replaced): the view, cleared for the new one, must not draw it again
            return
        if snap.seq != self._drawn_seq and t0 >= self._next_view_at:
            self._drawn_seq = snap.seq
            self.w.viewport.show_snapshot(snap)
            self.draws += 1
            if self.draws == 1:
                mark("first snapshot drawn")
            self._rate_draws += 1
            t1 = time.perf_counter()
            self.view_costs.append((t1 - t0) * 1000.0)
            self._next_view_at = t1 + VIEW_REST * (t1 - t0)
            self.w.method_errors.record(snap)  # a point per drawn frame; the plot redraws 4/s
            self.w.snapshotDrawn.emit(snap.frame)
        self._update_one_panel(snap, now, spent_ms=(time.perf_counter() - t0) * 1000.0)

    def _follow_playback(self, snap: Any) -> None:
        """The timeline follows the engine's frame while this play run goes on; paused, the
        session's own frame (a seek) stands, and a snapshot solved before it cannot move it
        back."""
        s = self.w.session
        if s.playing and snap.playing and snap.plays == s.plays:
            s.note_frame(snap.frame)

    def _mirror_engine(self, snap: Any) -> None:
        """Cheap state the session must know at once: the end of playback, a refused method."""
        s = self.w.session
        if self.w.busy.active:
            self.w.busy.check(snap)
        if s.playing and not snap.playing and snap.seq == self._drawn_seq and snap.plays == s.plays:
            s.note_frame(snap.frame)
            s.note_stopped()  # reached the end without looping
        if s.pause_pending and not snap.playing and snap.plays == s.plays:
            s.note_paused(snap.frame)  # the frame the view shows once paused
        refusal, self._refusal = self._refusal, None
        if refusal is None and snap.method_error:
            refusal = snap
        if refusal is not None and refusal.seq != self._refused_seq:  # the engine kept its method
            self._refused_seq = refusal.seq
            self.w.undo.refused(refusal.opened)  # the switch changed nothing: no undo step
            self.w.busy.end()  # nothing loads
            with self.w.undo.unrecorded():
                s.note_method(refusal.method)
            # after this tick: a modal box opened inside it would stop the drawing behind it
            error = refusal.method_error
            QTimer.singleShot(0, lambda: self.w.show_error("Cannot switch method", error))

    def _listen(self) -> None:
        """Hear every snapshot of the session's engine (a restarted engine is a new one)."""
        engine = self.w.session.engine
        if engine is not None and engine is not self._listened:
            engine.listeners.append(self._note_refusal)
            self._listened = engine

    def _note_refusal(self, snap: Any) -> None:
        """On the engine's thread: keep a snapshot that says a switch was refused."""
        if snap.method_error:
            self._refusal = snap

    def _update_one_panel(self, snap: Any, now: float, spent_ms: float) -> None:
        """Update the most overdue panel that has a newer snapshot than it showed.

        After a costly view draw the panel waits for a later tick, unless it is overdue
        by a whole interval (so a view drawing on every tick cannot starve the panels).
        """
        playing = snap.playing
        due = [p for p in self.panels if p.seq != snap.seq and (not playing or now - p.at >= p.interval_s)]
        if not due:
            return
        panel = min(due, key=lambda p: p.at)
        if playing and spent_ms > PANEL_BUDGET_MS and now - panel.at < 2 * panel.interval_s:
            return
        t = time.perf_counter()
        panel.update(snap)
        panel.costs.append((time.perf_counter() - t) * 1000.0)
        panel.seq, panel.at = snap.seq, now

    def _update_status(self, snap: Any) -> None:
        """Short texts that fit the status bar at 1600 px; the details are in tooltips."""
        w = self.w
        timing = snap.timing or {}
        per_it = timing.get("ms_per_iteration")
        solver = f"   {per_it:.2f} ms/it" if per_it is not None else ""
        skipped = f"   skipped {snap.frames_skipped}" if snap.pace == "real_time" else ""
        self._set_text(
            w.status_engine,
            f"solver {snap.engine_fps:4.0f} frames/s   {snap.ms:5.0f} ms/frame   {snap.iterations} it{solver}{skipped}",
        )
        parts = [
            f"{k.replace('fk_losses', 'fk+loss')} {timing[k]:.2f} ms"
            for k in ("decoder", "fk_losses", "backward", "step")
            if k in timing
        ]
        tip = [
            f"solver: {snap.engine_fps:.1f} frames solved per second (moving average)",
            f"last frame: {snap.ms:.1f} ms, {snap.iterations} iterations",
        ]
        if per_it is not None:
            tip.append(f"per iteration: {per_it:.2f} ms" + (f" ({', '.join(parts)})" if parts else ""))
        if "latency_ms" in timing:
            tip.append(f"live latency: {timing['latency_ms']:.0f} ms from packet to pose")
        if snap.pace == "real_time":
            tip.append(f"real-time playback skipped {snap.frames_skipped} clip frames the solver had not reached")
        self._set_tip(w.status_engine, "\n".join(tip))
        self._set_text(w.status_gui, f"view {self._draw_rate:3.0f} draws/s")
        self._set_text(w.status_warnings, f"warnings {snap.warnings}")
        # a warning both recent and of this frame is listed once
        self._set_tip(w.status_warnings, "\n".join(dict.fromkeys(snap.recent_errors + tuple(snap.messages))))
        w.ghost_status.on_snapshot(snap)
        w.optimizer_panel.set_settings_apply(snap.configurable, snap.method)
        # a ghost's error shows in its row; a stopped solver's last snapshot, drawn after
        # it died, must not replace the line that says why it stopped
        if snap.error and not w.ghost_status.is_ghost_problem(snap.error) and not self.engine_watch.stopped:
            w.statusBar().showMessage(snap.error, 5000)

    @staticmethod
    def _set_tip(label: Any, text: str) -> None:
        if label.toolTip() != text:
            label.setToolTip(text)

    @staticmethod
    def _set_text(label: Any, text: str) -> None:
        if label.text() != text:  # an unchanged label must not repaint
            label.setText(text)

    def costs(self) -> dict[str, dict[str, float]]:
        """Per panel (and ``view``): updates, mean, p99 and max cost in ms."""
        return {
            name: cost_summary(values)
            for name, values in [("view", self.view_costs)] + [(p.name, p.costs) for p in self.panels]
        }


def cost_summary(values: Any) -> dict[str, float]:
    """``updates``, ``mean_ms``, ``p99_ms`` and ``max_ms`` of costs in milliseconds."""
    a = np.asarray(values, float)
    return {
        "updates": int(a.size),
        "mean_ms": float(a.mean()) if a.size else 0.0,
        "p99_ms": float(np.percentile(a, 99)) if a.size else 0.0,
        "max_ms": float(a.max()) if a.size else 0.0,
    }
