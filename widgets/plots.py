"""Live optimizer plots (pyqtgraph): this frame's loss per iteration, costs and history.

* **Loss / iteration**: total and every term for the frame on screen (log y).
* **Cost / frame**: milliseconds and iterations of each solved frame over time (log y).
* **Loss history**: every term's final value per solved frame (log y).

The terms' legend is one list beside the plots (:class:`widgets.term_legend.TermLegend`):
it never covers a curve, scrolls when there are many terms, and untick hides a term in
every plot.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import pyqtgraph as pg
from PyQt6.QtGui import QCloseEvent
from PyQt6.QtWidgets import QHBoxLayout, QWidget

from widgets import style
from widgets.log_axis import LogAxis
from widgets.term_legend import TermLegend

pg.setConfigOptions(antialias=False, background=style.PLOT_BACKGROUND, foreground=style.PLOT_FOREGROUND)

MS_COLOUR, ITERATIONS_COLOUR = "#ff8a1f", "#4da3ff"
#: The widest y tick labels wanted on the log axes (:mod:`widgets.log_axis` picks only
#: labels that fit): the axes are made as wide, one width for all three plots
AXIS_LABELS = ("0.0000", "5·10⁻¹²")


#: Losses at or below this are a zero with float rounding (a squared error of a
#: micrometre): the hip sensor's position while the hip tracker sets the root comes out
#: of forward kinematics at about 1e-16, not exactly 0.
LOSS_FLOOR = 1e-12


def _loggable(value: float, floor: float = 0.0) -> float:
    """``value``, or NaN (a gap) when it is not above ``floor`` (a log axis cannot show 0).

    A term that is zero (the hip sensor's position while the hip tracker sets the root)
    drawn at its rounding error or a tiny floor instead would stretch the axis over ten
    decades and squash every other curve into one line.
    """
    return value if value > floor else np.nan


def _set_curve(item: pg.PlotDataItem, x: np.ndarray, y: np.ndarray) -> None:
    """Set a curve's data; one with nothing drawable is emptied (pyqtgraph warns on all-NaN)."""
    if np.isfinite(y).any():
        item.setData(x, y)
    else:
        item.setData([], [])


class CountAxis(pg.AxisItem):
    """A bottom axis that counts (frames, iterations): whole-number ticks only. Over a
    range of a unit or two pyqtgraph's own axis ticks 0.2, 0.4..., iterations and frames that do
    not exist."""

    def tickValues(self, minVal: float, maxVal: float, size: float) -> list:  # noqa: N802 (pyqtgraph's name)
        levels = []
        for spacing, values in super().tickValues(minVal, maxVal, size):
            if spacing < 1.0:  # finer than a unit: one tick per whole number, once
                spacing, values = 1.0, list(np.arange(np.ceil(minVal), np.floor(maxVal) + 1.0))
            whole = [v for v in values if float(v).is_integer()]
            if whole and all(spacing != s for s, _ in levels):
                levels.append((spacing, whole))
        return levels


def set_title(plot: pg.PlotWidget, title: str, why: str = "") -> None:
    """Set ``plot``'s (short, 9 pt) title and its tooltip ``why``, only when they change:
    a new title relayouts the plot and paints it a second time."""
    if plot.getPlotItem().titleLabel.text != title or plot.toolTip() != why:
        plot.setTitle(title, size="9pt")
        plot.setToolTip(why)


def show_empty(plot: pg.PlotWidget, title: str, why: str = "", sides: tuple[str, ...] = ("left",)) -> None:
    """Title ``plot``; with ``why`` (it draws nothing, and why not) say so in its tooltip
    and hide the values of its ``sides`` axes: they would be the last drawn data's, or
    pyqtgraph's 0..1 for no data (0.2, 0.4 ... of nothing), and an empty plot looked
    broken. Without ``why`` the values come back.
    """
    set_title(plot, title, why)
    for side in sides:
        axis = plot.getAxis(side)
        if axis.style["showValues"] == bool(why):
            axis.setStyle(showValues=not why)


def fit_frames(plot: pg.PlotWidget, x: np.ndarray, drawn: bool = True) -> None:
    """A frame axis over a few frames at least: with one solved frame the auto range
    spread frames -80 to 80 around it. With nothing ``drawn`` (every value 0 on a log
    axis) the axis still spans the frames ``x``: pyqtgraph's range for no data is 0..1."""
    vb = plot.getPlotItem().getViewBox()
    if len(x) and (not drawn or float(np.max(x) - np.min(x)) < 4.0):
        lo, hi = float(np.min(x)), float(np.max(x))
        if hi - lo < 4.0:
            lo, hi = 0.5 * (lo + hi) - 2.0, 0.5 * (lo + hi) + 2.0
        vb.setXRange(lo, hi, padding=0.0)  # turns the x auto range off
    elif not vb.autoRangeEnabled()[0]:
        vb.enableAutoRange(x=True)


def settle(plot: pg.PlotWidget) -> None:
    """Fit the plot's auto range to its new data now, not in the coming paint.

    pyqtgraph recomputes an auto range lazily when the view paints; the range change then
    asks for a second paint of the whole plot. Settling it right after the data changed
    makes one paint per update (a plot's paint costs 5-35 ms under software rendering).
    """
    if plot.isVisible():  # a hidden plot has no geometry to fit (and paints nothing)
        plot.getPlotItem().getViewBox().prepareForPaint()


def release(*plots: pg.PlotWidget) -> None:
    """Take every item out of ``plots`` (a closing view's teardown, as pyvistaqt's views
    drop their actors in ``close()``).

    A removed item belongs to Python again and dies with its last reference; one left in
    a plot is deleted with the window while a Python dict of ours may still hold it, and a
    Python wrapper over a deleted item is a crash waiting for a call (docs/reliability.md).
    """
    for plot in plots:
        plot.getPlotItem().clear()


def _plot(title: str, log_y: bool, x_label: str) -> pg.PlotWidget:
    # pyqtgraph's own log axis labels every 1..9 multiple on a range of a decade or two,
    # one label over the other: LogAxis labels only what fits (decades, 1-2-5, ...)
    w = pg.PlotWidget(axisItems={"left": LogAxis("left"), "bottom": CountAxis("bottom")})
    # short titles in a small font: a title wider than the plot kept the plot item from
    # shrinking, and the plots beside it cut it off
    w.setTitle(title, size="9pt")
    w.setLogMode(y=log_y)
    # no grid: its translucent lines cost ~8 ms per repaint under software rendering
    w.setLabel("bottom", x_label)
    # frames past 1000 would read "frame (x0.001)": axes here count frames and iterations
    for side in ("bottom", "left"):
        w.getAxis(side).enableAutoSIPrefix(False)
    # a fixed label column: tick labels of a new width would relayout the plot and paint
    # it a second time
    left = w.getAxis("left")
    left.setWidth(left.width_for(AXIS_LABELS))
    w.setMinimumHeight(120)
    return w


class _Curves:
    """Curves by term name in one plot, created on first sight with a stable colour."""

    def __init__(self, plot: pg.PlotWidget, colours: dict[str, str], legend: TermLegend) -> None:
        self.plot, self.colours, self.legend, self.items = plot, colours, legend, {}

    def get(self, name: str, symbols: bool = False) -> pg.PlotDataItem:
        if name not in self.items:
            colour = self.colours.setdefault(name, style.term_colour(len(self.colours) - 1))
            # wide pens go through Qt's stroker: fine for a few points per iteration,
            # costly for a long history, which uses 1 px lines (the total is white)
            width = (2.5 if name == "total" else 1.5) if symbols else 1.0
            # the iterations are marked on the total only (markers on every term doubled
            # the plot's repaint cost)
            marks = (
                dict(symbol="o", symbolSize=5, symbolBrush=colour, symbolPen=None)
                if symbols and name == "total"
                else {}
            )
            self.items[name] = self.plot.plot(pen=pg.mkPen(colour, width=width), **marks)
            self.items[name].setVisible(self.legend.visible(name))
        return self.items[name]

    def keep_only(self, names: set[str]) -> None:
        """Drop the curves of terms that left (a removed sensor or constraint)."""
        for name in [n for n in self.items if n not in names]:
            self.plot.removeItem(self.items.pop(name))

    def set_visible(self, name: str, on: bool) -> None:
        if name in self.items:
            self.items[name].setVisible(on)

    def reset(self) -> None:
        self.plot.clear()
        self.items = {}


class LossPlots(QWidget):
    """Feed it snapshots with :meth:`update_snapshot`; it redraws only on new data."""

    def __init__(self, parent: QWidget | None = None) -> None:
        super().__init__(parent)
        colours: dict[str, str] = {"total": "#ffffff"}
        self.colours = colours
        self.legend = TermLegend()
        self.iteration_plot = _plot("Loss per iteration", True, "iteration (0: start)")
        # log y: the first frame of a clip is solved offline (seconds) and would flatten
        # the steady per-frame cost (tens of ms) on a linear axis
        self.cost_plot = _plot(
            f"<span style='color:{MS_COLOUR}'>ms</span> and <span style='color:{ITERATIONS_COLOUR}'>iterations</span>",
            True,
            "frame",
        )
        self.history_plot = _plot("Loss history", True, "frame")
        self.iter_curves = _Curves(self.iteration_plot, colours, self.legend)
        self.history_curves = _Curves(self.history_plot, colours, self.legend)
        self.legend.visibilityChanged.connect(self._set_visible)
        self.ms_curve = self.cost_plot.plot(pen=pg.mkPen(MS_COLOUR, width=1))
        self.iter_curve = self.cost_plot.plot(pen=pg.mkPen(ITERATIONS_COLOUR, width=1))
        # one row: each plot gets the dock's full height (stacked two high they would be
        # ~100 px each at 1600 x 1000, their curves on top of one another)
        plots = QHBoxLayout()
        plots.addWidget(self.iteration_plot, 4)
        plots.addWidget(self.cost_plot, 3)
        plots.addWidget(self.history_plot, 4)
        layout = QHBoxLayout(self)
        layout.setContentsMargins(0, 0, 0, 0)
        layout.addLayout(plots, 1)
        layout.addWidget(self.legend)
        self._seq = -1

    def _set_visible(self, name: str, on: bool) -> None:
        self.iter_curves.set_visible(name, on)
        self.history_curves.set_visible(name, on)

    def closeEvent(self, event: QCloseEvent | None) -> None:  # noqa: N802 (Qt's name)
        """Drop every curve: a closed view holds no plot item (:func:`release`)."""
        self.iter_curves.items, self.history_curves.items = {}, {}
        release(self.iteration_plot, self.cost_plot, self.history_plot)
        super().closeEvent(event)

    def clear(self) -> None:
        self.ms_curve.setData([], [])
        self.iter_curve.setData([], [])
        self.history_curves.reset()
        self.iter_curves.reset()
        self.legend.set_terms((), self.colours)

    def update_snapshot(self, snap: Any) -> None:
        """Draw ``snap`` in all three plots (the window spreads them over display ticks
        with :meth:`update_iterations`, :meth:`update_cost` and :meth:`update_history`).

        The history comes from the engine (``snap.history``), so frames whose snapshots
        were never drawn still appear; it restarts when playback jumps or loops. The
        terms shown are this frame's: older frames' terms that left are dropped.
        """
        if snap.seq == self._seq:
            return
        self._seq = snap.seq
        self.update_iterations(snap)
        self.update_cost(snap)
        self.update_history(snap)

    def _terms(self, snap: Any) -> list[str]:
        """This frame's terms; the legend and curves follow them (rebuilt only when the
        set changes, see :meth:`widgets.term_legend.TermLegend.set_terms`)."""
        losses, history = snap.losses, snap.history
        names = list(losses[-1]) if losses else list(history[-1].losses) if history else []
        if tuple(names) != self.legend.terms:
            current = set(names)
            self.iter_curves.keep_only(current)
            self.history_curves.keep_only(current)
            for name in names:  # colours first, so the legend shows the curves' colours
                self.iter_curves.get(name, symbols=True)
            self.legend.set_terms(tuple(names), self.colours)
        return names

    def _all_zero(self, plot: pg.PlotWidget, title: str, zero: bool) -> None:
        """``plot``'s own ``title``, or with ``zero`` (every term 0: nothing a log axis can
        draw) the title and a tooltip saying so, and no loss values on the y axis."""
        why = "Every term is 0 (the method meets each tracker exactly): a log axis has nothing to draw."
        show_empty(plot, title + (": all 0" if zero else ""), why if zero else "")

    def update_iterations(self, snap: Any) -> None:
        """This frame's loss per iteration, every term."""
        names = self._terms(snap)
        losses = snap.losses
        drawn = False
        if losses:
            # the loss at the start latent, then after each step: x 0..N for N iterations,
            # as the status bar and the latent map count them
            its = np.arange(len(losses))
            for name in names:
                vals = np.array([_loggable(float(d.get(name, np.nan)), LOSS_FLOOR) for d in losses])
                _set_curve(self.iter_curves.get(name, symbols=True), its, vals)
                drawn = drawn or bool(np.isfinite(vals).any())
            vb = self.iteration_plot.getPlotItem().getViewBox()
            if not drawn:  # all 0: the iterations run, not pyqtgraph's 0..1 for no data
                vb.setXRange(-0.5, len(losses) - 0.5, padding=0.0)
            elif not vb.autoRangeEnabled()[0]:
                vb.enableAutoRange(x=True)
            settle(self.iteration_plot)
        if not losses and snap.history:
            method = getattr(snap, "method", "") or "this method"
            show_empty(
                self.iteration_plot, "Loss per iteration: none", f"{method} does not iterate: it reports no loss."
            )
        else:
            self._all_zero(self.iteration_plot, "Loss per iteration", bool(names) and bool(losses) and not drawn)

    def update_cost(self, snap: Any) -> None:
        """Milliseconds and iterations of the engine's recent solved frames."""
        history = snap.history
        x = np.array([r.frame for r in history], float)
        _set_curve(self.ms_curve, x, np.array([_loggable(r.ms) for r in history], float))
        _set_curve(self.iter_curve, x, np.array([_loggable(r.iterations) for r in history], float))
        fit_frames(self.cost_plot, x)
        settle(self.cost_plot)

    def update_history(self, snap: Any) -> None:
        """Every current term's final loss over the engine's recent solved frames."""
        names = self._terms(snap)
        history = snap.history
        x = np.array([r.frame for r in history], float)
        shown = False
        for name in names:
            y = np.array([_loggable(float(r.losses.get(name, np.nan)), LOSS_FLOOR) for r in history])
            _set_curve(self.history_curves.get(name), x, y)
            shown = shown or bool(np.isfinite(y).any())
        self._all_zero(self.history_plot, "Loss history", bool(names) and not shown)
        fit_frames(self.history_plot, x, drawn=shown)
        settle(self.history_plot)
