"""``dragposer-studio gui FILE --measure SECONDS --json OUT.json``: how smooth the studio is.

Plays the clip in the real window for SECONDS (after the first solved frame of
playback) and writes:

* ``draws_per_s``: 3D-view draws per second;
* ``solved_per_s``: frames the engine solved per second;
* ``frames_skipped``: clip frames playback passed over unsolved (0 at the "every frame" pace);
* ``event_loop_ms``: lateness of a 10 ms timer on the GUI thread (``p50``, ``p99``,
  ``max``): how long the window can be unresponsive;
* ``panels``: per panel (and the 3D ``view``) the number of updates and their mean, p99
  and max cost in ms, as measured around each update on the GUI thread, plus
  ``paint:plots``: the repaints of every pyqtgraph view (the plots and the latent
  panel), which Qt runs later, outside the updates;

plus what was measured (clip, method, sensors, pace, window size, platform). The JSON
is written to a temporary file and renamed.
"""

from __future__ import annotations

import json
import os
import platform
import time
from collections.abc import Callable
from typing import Any

import numpy as np
from PyQt6.QtCore import Qt, QTimer
from PyQt6.QtGui import QGuiApplication

from app.drawing import cost_summary
from app.shell import StudioShell
from engine.atomic import write_text

PROBE_MS = 10  # the lateness probe's period
START_TIMEOUT_S = 120.0  # the first solve of a clip (model load, offline frame) may be slow


class Measurement:
    """Plays ``window``'s clip and measures for ``seconds``; ``done(code)`` is called at the end."""

    def __init__(self, window: StudioShell, seconds: float, out: str, done: Callable[[int, str], None]) -> None:
        self.w, self.seconds, self.out, self.done = window, float(seconds), out, done
        self.lateness: list[float] = []
        self._probe = QTimer(window, interval=PROBE_MS)
        self._probe.setTimerType(Qt.TimerType.PreciseTimer)
        self._probe.timeout.connect(self._tick)
        self._last = 0.0
        self._start: dict[str, Any] = {}
        self.paint_costs: list[float] = []
        self._t0 = time.monotonic()
        self._waiting = QTimer(window, interval=50)
        self._waiting.timeout.connect(self._maybe_start)

    def begin(self) -> None:
        self._time_plot_paints()
        self.w.session.set_playing(True)
        self._waiting.start()

    def _time_plot_paints(self) -> None:
        """Time every pyqtgraph view's paint event (this process only measures, so the
        class is patched for the rest of it)."""
        import pyqtgraph as pg

        costs = self.paint_costs = []
        paint = pg.GraphicsView.paintEvent

        def timed(view: Any, event: Any) -> Any:
            t = time.perf_counter()
            try:
                return paint(view, event)
            finally:
                if self._start:
                    costs.append((time.perf_counter() - t) * 1000.0)

        pg.GraphicsView.paintEvent = timed

    def _maybe_start(self) -> None:
        """Start once playback has solved a frame (the load and first solve are not measured)."""
        snap = self.w.session.latest
        if snap is None or not snap.playing or snap.solved < 2:
            if time.monotonic() - self._t0 > START_TIMEOUT_S:
                self._waiting.stop()
                self.done(1, f"error: playback did not start within {START_TIMEOUT_S:.0f} s")
            return
        self._waiting.stop()
        d = self.w.drawing
        d.view_costs.clear()
        for p in d.panels:
            p.costs.clear()
        self._start = {"t": time.monotonic(), "draws": d.draws, "solved": snap.solved, "skipped": snap.frames_skipped}
        self._last = time.perf_counter()
        self._probe.start()
        QTimer.singleShot(int(self.seconds * 1000), self._finish)

    def _tick(self) -> None:
        now = time.perf_counter()
        self.lateness.append(max(0.0, (now - self._last) * 1000.0 - PROBE_MS))
        self._last = now

    def _finish(self) -> None:
        self._probe.stop()
        elapsed = time.monotonic() - self._start["t"]
        snap = self.w.session.latest
        self.w.session.set_playing(False)
        late = np.asarray(self.lateness or [0.0], float)
        s = self.w.session
        result = {
            "command": "dragposer-studio gui FILE --measure SECONDS --json OUT.json",
            "seconds": round(elapsed, 3),
            "draws_per_s": (self.w.drawing.draws - self._start["draws"]) / elapsed,
            "solved_per_s": (snap.solved - self._start["solved"]) / elapsed,
            "frames_skipped": int(snap.frames_skipped - self._start["skipped"]),
            "event_loop_ms": {
                "p50": float(np.percentile(late, 50)),
                "p99": float(np.percentile(late, 99)),
                "max": float(late.max()),
                "samples": int(late.size),
            },
            "panels": {**self.w.drawing.costs(), "paint:plots": cost_summary(self.paint_costs)},
            "clip": str(s.path) if s.path else "(generated)",
            "method": s.method,
            "sensors": [sn.joint for sn in s.sensors.values() if sn.enabled],
            "constraints": [f"{c.name} ({c.kind})" for c in s.constraints if c.enabled],
            "pace": s.pace,
            "window": [self.w.width(), self.w.height()],
            "platform": {
                "qt": QGuiApplication.platformName(),
                "display": os.environ.get("DISPLAY", ""),
                "cpus": os.cpu_count(),
                "python": platform.python_version(),
            },
            "solver_timing_ms": dict(snap.timing),
        }
        write_text(self.out, json.dumps(result, indent=2) + "\n")
        self.done(0, "")
