"""Term forces of the frame on screen: which loss term pulls the latent, how hard, where.

*Inspect this frame* asks the engine (``inspectRequested(joint)``) for the frame's
detail: each term's force on the latent (minus the gradient of its weighted loss) at
every iteration of its solve (docs/latent.md). The top chart shows each term's force
norm at the chosen iteration, in the term's colour from the loss plots; the bottom one
the chosen term's force per latent dimension (or, with a joint chosen, each dimension's
influence on that joint). It starts on the first term with a force (a term can push
nothing, e.g. a sensor already met), and says "no force" rather than stay blank. Terms whose forces point against each other are named.

The norms are horizontal bars with the terms named on the left: names under vertical
bars ran into each other ("rankletemporal_prior") in the dock's ~460 px. Until a frame
is inspected (or with a method that has no latent) both charts say so in their titles
and tooltips and show no axis values (:func:`widgets.plots.show_empty`).
"""

from __future__ import annotations

from typing import Any

import numpy as np
import pyqtgraph as pg
from PyQt6.QtCore import pyqtSignal
from PyQt6.QtGui import QCloseEvent, QFont, QFontMetricsF
from PyQt6.QtWidgets import QComboBox, QGridLayout, QLabel, QPushButton, QSpinBox, QVBoxLayout, QWidget

from engine import skeleton as sk
from widgets import style
from widgets.plots import CountAxis, release, settle, show_empty

INFLUENCE = "influence on the joint"
NORM_TITLE = "force norm per term"
DIM_TITLE = "per latent dimension"
#: What the tab says while it holds no inspection (at the start and after each solve).
EMPTY = (
    "Empty until Inspect this frame: the forces are drawn for the frame inspected, "
    "until the next solve (an edit, another frame)."
)


def conflicts(forces: np.ndarray, names: tuple[str, ...], limit: float = -0.5) -> list[str]:
    """``"a vs b"`` for terms whose forces ``(T, L)`` have a cosine below ``limit``."""
    n = np.linalg.norm(forces, axis=1)
    out = []
    for i in range(len(names)):
        for j in range(i + 1, len(names)):
            if n[i] > 1e-12 and n[j] > 1e-12 and forces[i] @ forces[j] / (n[i] * n[j]) < limit:
                out.append(f"{names[i]} vs {names[j]}")
    return out


def first_with_force(forces: np.ndarray) -> int:
    """The first term whose force ``(K, T, L)`` is not zero at some iteration (0 if none)."""
    moving = np.flatnonzero(np.any(np.asarray(forces) != 0, axis=(0, 2)))
    return int(moving[0]) if moving.size else 0


def short_name(term: str) -> str:
    """A term's name in the chart: a sensor's term is its joint (the tooltip has it whole)."""
    return term.removeprefix("sensor:")


class TermAxis(pg.AxisItem):
    """The left axis of horizontal bars: one term name per bar, right-aligned.

    The names are handed over as three tick levels (every fourth, the others of every
    second, the rest): pyqtgraph draws a level only while its text fits, so a short
    panel names every second or fourth bar instead of printing names over each other.
    The axis is as wide as the widest name (pyqtgraph sized it from all but the last
    level and dropped the names that did not fit).
    """

    def __init__(self, orientation: str = "left", **kwargs: Any) -> None:
        super().__init__(orientation, **kwargs)
        self.setStyle(maxTextLevel=2, textFillLimits=[(0, 0.9)])
        self.names: tuple[str, ...] = ()

    def set_names(self, names: tuple[str, ...]) -> None:
        """Name the bars at y = 0, 1, ... (top to bottom in an inverted view)."""
        if names == self.names:
            return
        self.names = names
        rows = list(enumerate(names))
        self.setTicks([rows[::4], rows[2::4], rows[1::2]])
        if names:
            metrics = QFontMetricsF(self.style["tickFont"] or QFont())
            widest = max(metrics.horizontalAdvance(n) for n in names)
            self.setWidth(int(widest + max(0, self.style["tickLength"]) + self.style["tickTextOffset"][0] + 2))


class LatentForces(QWidget):
    """See the module doc. ``colours`` is the loss plots' term-colour dict (shared)."""

    inspectRequested = pyqtSignal(str)

    def __init__(self, colours: dict[str, str] | None = None, parent: QWidget | None = None) -> None:
        super().__init__(parent)
        self.colours = colours if colours is not None else {"total": "#ffffff"}
        layout = QVBoxLayout(self)
        layout.setContentsMargins(0, 0, 0, 0)
        grid = QGridLayout()
        self.inspect_button = QPushButton("Inspect this frame")
        self.inspect_button.setToolTip(
            "Pause and compute this frame's term forces and dimension sweep (about a second)"
        )
        self.inspect_button.clicked.connect(lambda: self.inspectRequested.emit(self.joint.currentData() or ""))
        self.joint = QComboBox(toolTip="A joint: its most influential latent dimensions")
        self.joint.addItem("(no joint)", "")
        for name in sk.JOINT_NAMES:
            self.joint.addItem(name, name)
        self.iteration = QSpinBox(prefix="iteration ", minimum=0, maximum=0)
        self.iteration.valueChanged.connect(lambda _: self._draw())
        self.term = QComboBox(toolTip="Whose force to show per latent dimension")
        self.term.currentIndexChanged.connect(lambda _: self._draw())
        self.info = QLabel(EMPTY)
        self.info.setWordWrap(True)
        grid.addWidget(self.inspect_button, 0, 0)
        grid.addWidget(self.joint, 0, 1)
        grid.addWidget(self.iteration, 1, 0)
        grid.addWidget(self.term, 1, 1)
        layout.addLayout(grid)
        layout.addWidget(self.info)
        self.term_axis = TermAxis()
        self.norm_plot = pg.PlotWidget(axisItems={"left": self.term_axis})
        self.norm_plot.setMinimumHeight(110)
        self.norm_plot.getPlotItem().getViewBox().invertY(True)  # the first term on top
        self.norm_plot.getAxis("bottom").enableAutoSIPrefix(False)
        self.norm_bars = pg.BarGraphItem(x0=0.0, y=[], height=0.8, width=[])
        self.norm_plot.addItem(self.norm_bars)
        self.dim_plot = pg.PlotWidget(axisItems={"bottom": CountAxis("bottom")})
        self.dim_plot.setMinimumHeight(110)
        self.dim_plot.setLabel("bottom", "latent dimension")
        self.dim_bars = pg.BarGraphItem(x=[], height=[], width=0.8)
        self.dim_plot.addItem(self.dim_bars)
        layout.addWidget(self.norm_plot, 1)
        layout.addWidget(self.dim_plot, 1)
        self.detail: Any = None
        self.note = ""
        self._draw()

    def closeEvent(self, event: QCloseEvent | None) -> None:  # noqa: N802 (Qt's name)
        """A closed view holds no plot item (:func:`widgets.plots.release`)."""
        release(self.norm_plot, self.dim_plot)
        super().closeEvent(event)

    def colour(self, name: str) -> str:
        """A term's colour, as the loss plots give it (assigned here first if new)."""
        return self.colours.setdefault(name, style.term_colour(len(self.colours) - 1))

    def set_detail(self, detail: Any, note: str = "") -> None:
        """Show a :class:`~engine.studio.latent_views.LatentDetail`; None clears, and
        ``note`` then says why there is none (e.g. a method without a latent space)."""
        if detail is self.detail and note == self.note:
            return
        self.detail, self.note = detail, note
        self.term.blockSignals(True)
        self.term.clear()
        if detail is not None:
            for name in detail.names:
                self.term.addItem(name, name)
            if detail.influence is not None:
                self.term.addItem(f"{INFLUENCE} {detail.joint}", INFLUENCE)
                self.term.setCurrentIndex(self.term.count() - 1)
            else:
                self.term.setCurrentIndex(first_with_force(detail.forces))
        self.term.blockSignals(False)
        self.iteration.blockSignals(True)
        self.iteration.setMaximum(max(0, len(detail.forces) - 1) if detail is not None else 0)
        self.iteration.setValue(0)
        self.iteration.blockSignals(False)
        self._draw()

    def _draw(self) -> None:
        d = self.detail
        if d is None:
            # nothing inspected since the last solve: no term, iteration or frame of an
            # earlier inspection is named over the empty charts
            why = self.note or EMPTY
            self.norm_bars.setOpts(y=[], width=[])
            self.dim_bars.setOpts(x=[], height=[])
            self.term_axis.set_names(())
            show_empty(self.norm_plot, f"{NORM_TITLE}: none", why, sides=("left", "bottom"))
            show_empty(self.dim_plot, f"{DIM_TITLE}: none", why, sides=("left", "bottom"))
            self.info.setText(why)
            return
        k = min(self.iteration.value(), len(d.forces) - 1)
        f = np.asarray(d.forces[k])
        norms = np.linalg.norm(f, axis=1)
        self.norm_bars.setOpts(y=np.arange(len(d.names)), width=norms, brushes=[self.colour(n) for n in d.names])
        self.term_axis.set_names(tuple(short_name(n) for n in d.names))
        show_empty(self.norm_plot, NORM_TITLE, sides=("left", "bottom"))
        # every name whole with its norm, also those a short panel leaves unlabelled
        self.norm_plot.setToolTip("<br>".join(f"{n}: {v:.3g}" for n, v in zip(d.names, norms)))
        chosen = self.term.currentData()
        if chosen == INFLUENCE and d.influence is not None:
            self.dim_bars.setOpts(x=np.arange(len(d.influence)), height=d.influence, brush=style.SENSOR)
            show_empty(self.dim_plot, f"|d {d.joint} / d z| (m per latent unit)", sides=("left", "bottom"))
        elif chosen in d.names:
            t = d.names.index(chosen)
            self.dim_bars.setOpts(x=np.arange(f.shape[1]), height=f[t], brush=self.colour(chosen))
            none = "" if np.any(f[t] != 0) else ": no force"
            show_empty(self.dim_plot, f"force of {chosen}, iteration {k}{none}", sides=("left", "bottom"))
        against = conflicts(f, d.names)
        self.info.setText(
            # forces at the start and after each step: one more than the solver's iterations
            f"frame {d.frame}, {len(d.forces) - 1} iterations, {d.ms:.0f} ms"
            + (f"; pulling against each other: {', '.join(against)}" if against else "")
        )
        settle(self.norm_plot)
        settle(self.dim_plot)
