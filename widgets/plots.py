"""Live optimizer plots (pyqtgraph): this frame's loss per iteration, costs and history.

* **Loss / iteration**: total and every term for the frame on screen (log y).
* **Cost / frame**: milliseconds and iterations of each solved frame over time (log y).
* **Loss history**: every term's final value per solved frame (log y).

Click a legend entry to hide or show that term (pyqtgraph's legend does the toggling).
"""

from __future__ import annotations

from typing import Any

import numpy as np
import pyqtgraph as pg
from PyQt6.QtWidgets import QHBoxLayout, QVBoxLayout, QWidget

from widgets import style

pg.setConfigOptions(antialias=False, background=style.PLOT_BACKGROUND, foreground=style.PLOT_FOREGROUND)

LEGEND_COLUMNS = 4


def _loggable(value: float) -> float:
    """``value``, or NaN (a gap) when a log axis cannot show it.

    A term that is exactly zero (the hip sensor's position while the hip tracker sets
    the root) drawn at a tiny floor instead would stretch the axis over ten decades and
    squash every other curve into one line.
    """
    return value if value > 0 else np.nan


def _set_curve(item: pg.PlotDataItem, x: np.ndarray, y: np.ndarray) -> None:
    """Set a curve's data; one with nothing drawable is emptied (pyqtgraph warns on all-NaN)."""
    if np.isfinite(y).any():
        item.setData(x, y)
    else:
        item.setData([], [])


def _plot(title: str, log_y: bool, x_label: str) -> pg.PlotWidget:
    w = pg.PlotWidget(title=title)
    w.setLogMode(y=log_y)
    w.showGrid(x=True, y=True, alpha=0.2)
    w.setLabel("bottom", x_label)
    # rows of four: a one-entry-per-row legend of ~8 terms is taller than the plot and
    # cut off, which left most terms impossible to click; a half-clear backdrop keeps
    # the labels readable over the curves without hiding them
    backdrop = (*style.hex_to_rgb(style.PLOT_BACKGROUND), 160)
    w.addLegend(offset=(-5, 5), labelTextSize="8pt", colCount=LEGEND_COLUMNS, brush=backdrop)
    w.setMinimumHeight(120)
    return w


class _Curves:
    """Curves by term name in one plot, created on first sight with a stable colour."""

    def __init__(self, plot: pg.PlotWidget, colours: dict[str, str]) -> None:
        self.plot, self.colours, self.items = plot, colours, {}
        self.hidden: set[str] = set()  # terms hidden from the legend stay hidden after a reset

    def get(self, name: str, symbols: bool = False) -> pg.PlotDataItem:
        if name not in self.items:
            colour = self.colours.setdefault(name, style.TERM_CYCLE[len(self.colours) % len(style.TERM_CYCLE)])
            width = 2.5 if name == "total" else 1.5
            marks = dict(symbol="o", symbolSize=5, symbolBrush=colour, symbolPen=None) if symbols else {}
            self.items[name] = self.plot.plot(name=name, pen=pg.mkPen(colour, width=width), **marks)
            self.items[name].setVisible(name not in self.hidden)
        return self.items[name]

    def reset(self) -> None:
        self.hidden = (self.hidden - set(self.items)) | {n for n, it in self.items.items() if not it.isVisible()}
        self.plot.clear()
        if self.plot.plotItem.legend is not None:
            self.plot.plotItem.legend.clear()
        self.items = {}


class LossPlots(QWidget):
    """Feed it snapshots with :meth:`update_snapshot`; it redraws only on new data."""

    def __init__(self, parent: QWidget | None = None) -> None:
        super().__init__(parent)
        colours: dict[str, str] = {"total": "#ffffff"}
        self.iteration_plot = _plot("Loss per iteration (this frame)", True, "iteration")
        # log y: the first frame of a clip is solved offline (seconds) and would flatten
        # the steady per-frame cost (tens of ms) on a linear axis
        self.cost_plot = _plot("Cost per frame (ms, iterations)", True, "frame")
        self.history_plot = _plot("Loss history", True, "frame")
        self.iter_curves = _Curves(self.iteration_plot, colours)
        self.history_curves = _Curves(self.history_plot, colours)
        self.ms_curve = self.cost_plot.plot(name="ms", pen=pg.mkPen("#ff8a1f", width=1.5))
        self.iter_curve = self.cost_plot.plot(name="iterations", pen=pg.mkPen("#4da3ff", width=1.5))
        layout = QVBoxLayout(self)
        layout.setContentsMargins(0, 0, 0, 0)
        layout.addWidget(self.iteration_plot, 1)
        row = QHBoxLayout()
        row.addWidget(self.cost_plot, 1)
        row.addWidget(self.history_plot, 1)
        layout.addLayout(row, 1)
        self._seq = -1

    def clear(self) -> None:
        self.ms_curve.setData([], [])
        self.iter_curve.setData([], [])
        self.history_curves.reset()
        self.iter_curves.reset()

    def update_snapshot(self, snap: Any) -> None:
        """Draw ``snap``: its iterations, and the engine's record of recent frames.

        The history comes from the engine (``snap.history``), so frames whose snapshots
        were never drawn still appear; it restarts when playback jumps or loops.
        """
        if snap.seq == self._seq:
            return
        self._seq = snap.seq
        history = tuple(snap.history)
        losses = snap.losses
        if losses:
            its = np.arange(1, len(losses) + 1)
            names = list(losses[-1])
            for name in names:
                vals = np.array([_loggable(float(d.get(name, np.nan))) for d in losses])
                _set_curve(self.iter_curves.get(name, symbols=True), its, vals)
            for name, item in self.iter_curves.items.items():
                if name not in names:
                    item.setData([], [])
        x = np.array([r.frame for r in history], float)
        _set_curve(self.ms_curve, x, np.array([_loggable(r.ms) for r in history], float))
        _set_curve(self.iter_curve, x, np.array([_loggable(r.iterations) for r in history], float))
        names = dict.fromkeys(n for r in history for n in r.losses)
        for name in names:
            y = np.array([_loggable(float(r.losses.get(name, np.nan))) for r in history])
            _set_curve(self.history_curves.get(name), x, y)
        for name, item in self.history_curves.items.items():
            if name not in names:
                item.setData([], [])
