"""Per-method error against the ground truth, frame by frame (pyqtgraph).

One curve per method on screen: the selected method (the reconstruction's colour) and
every ghost method (its ghost colour), each the mean joint distance in centimetres
between that method's pose and the loaded clip's pose on the frame shown. Frames the
reader skipped leave gaps; a jump (seek back or far ahead, loop, new clip or method)
starts the curves again, as it starts the engine's history again. The legend beside the plot lists the methods with their current
error.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import pyqtgraph as pg
from PyQt6.QtGui import QCloseEvent
from PyQt6.QtWidgets import QHBoxLayout, QLabel, QVBoxLayout, QWidget

from widgets import style
from widgets.plots import CountAxis, fit_frames, release, settle

#: Frames kept per curve (older ones scroll out).
KEEP = 3000


def frame_error_cm(positions: np.ndarray | None, truth: np.ndarray | None) -> float:
    """Mean joint distance ``(22, 3)`` vs ``(22, 3)`` in cm; NaN when either is missing."""
    if positions is None or truth is None or np.shape(positions) != np.shape(truth):
        return float("nan")
    d = np.linalg.norm(np.asarray(positions, float) - np.asarray(truth, float), axis=-1).mean()
    return float(100.0 * d)


class MethodErrorPlot(QWidget):
    """Feed it snapshots with :meth:`update_snapshot`."""

    def __init__(self, parent: QWidget | None = None) -> None:
        super().__init__(parent)
        # frames are whole: over a few frames pyqtgraph's own axis ticks 0.5, 1.5...
        self.plot = pg.PlotWidget(
            title="Error against the ground truth (cm, mean over joints)", axisItems={"bottom": CountAxis("bottom")}
        )
        self.plot.showGrid(x=True, y=True, alpha=0.2)
        self.plot.setLabel("bottom", "frame")
        for side in ("bottom", "left"):
            self.plot.getAxis(side).enableAutoSIPrefix(False)
        self.plot.setMinimumHeight(120)
        self.legend = QLabel()
        self.legend.setTextFormat(pg.QtCore.Qt.TextFormat.RichText)
        self.legend.setMinimumWidth(150)
        side = QVBoxLayout()
        side.addWidget(self.legend)
        side.addStretch(1)
        layout = QHBoxLayout(self)
        layout.setContentsMargins(0, 0, 0, 0)
        layout.addWidget(self.plot, 1)
        layout.addLayout(side)
        self.curves: dict[str, pg.PlotDataItem] = {}
        self.data: dict[str, dict[int, float]] = {}
        self._seq, self._last_frame, self._recorded = -1, -1, -1
        self._run = 0  # the engine's history_run the curves belong to

    def colour(self, name: str, index: int, main: bool) -> str:
        return style.RECONSTRUCTION if main else style.ghost_color(name, index)

    def closeEvent(self, event: QCloseEvent | None) -> None:  # noqa: N802 (Qt's name)
        """Drop every curve: a closed view holds no plot item (:func:`widgets.plots.release`)."""
        self.clear()
        release(self.plot)
        super().closeEvent(event)

    def clear(self) -> None:
        for c in self.curves.values():
            self.plot.removeItem(c)
        self.curves, self.data, self._last_frame = {}, {}, -1
        self.legend.setText("")

    def record(self, snap: Any) -> dict[str, float]:
        """Keep this snapshot's errors (the selected method and every ghost) without
        drawing; called for every drawn snapshot, so the curves have a point per drawn
        frame even though the plot redraws a few times a second. Returns them by name."""
        main = snap.method or "reconstruction"
        errors = {main: frame_error_cm(snap.positions, snap.ground_truth)}
        for name, pos in snap.ghosts.items():
            errors[name] = frame_error_cm(pos, snap.ground_truth)
        if snap.seq == self._recorded:
            return errors
        self._recorded = snap.seq
        # the frame before a jump may never have been drawn (the window draws only the
        # newest snapshot), so the engine's count of history restarts decides
        if snap.frame < self._last_frame or snap.history_run != self._run:
            self.clear()
            self._run = snap.history_run
        self._last_frame = snap.frame
        for name, err in errors.items():
            series = self.data.setdefault(name, {})
            series[snap.frame] = err
            if len(series) > KEEP:
                for f in sorted(series)[: len(series) - KEEP]:
                    del series[f]
        return errors

    def update_snapshot(self, snap: Any) -> None:
        """Add this snapshot's errors and redraw the curves."""
        if snap.seq == self._seq:
            return
        self._seq = snap.seq
        errors = self.record(snap)
        main = snap.method or "reconstruction"
        for name in list(self.curves):
            if name not in errors:  # a method no longer shown
                self.plot.removeItem(self.curves.pop(name))
                self.data.pop(name, None)
        rows = []
        for i, (name, err) in enumerate(errors.items()):
            colour = self.colour(name, i - 1, name == main)
            if name not in self.curves:
                self.curves[name] = self.plot.plot(pen=pg.mkPen(colour, width=1), name=name)
            series = self.data.setdefault(name, {})
            x = np.array(sorted(series), float)
            y = np.array([series[int(f)] for f in x], float)
            if np.isfinite(y).any():
                self.curves[name].setData(x, y, connect="finite")
            rows.append(
                f"<span style='color:{colour}'>&#9644; {name}</span>: "
                + ("-" if not np.isfinite(err) else f"{err:.1f} cm")
            )
        self.legend.setText("<br>".join(rows))
        fit_frames(self.plot, np.array(sorted(self.data.get(main, {})), float))
        settle(self.plot)
