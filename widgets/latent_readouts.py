"""Prior readouts over the solved frames, with the flagged frames and a jump to the next.

Three curves over every frame solved since the clip or method was opened (a
:class:`engine.latent.solved_frames.SolvedFrames`, shared with the latent map): the
distance to the nearest training latent, the latent norm and the distance from the prior
latent (docs/latent.md). Each flag threshold is dashed in its curve's colour and named;
a flagged frame is a red cross on the curve that crossed its threshold. *Next flagged
frame* emits ``seekRequested(frame)`` for the first flagged frame after the one on
screen (wrapping to the first); ``flagsChanged(frames)`` lets the timeline mark them.

The line above the chart states the frame on screen's readouts beside the thresholds
and the verdict, all from one solve. A frame solved again after a seek may no longer be
flagged (its temporal state differs from playback's): the line then says what the
earlier, flagged solve read.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import pyqtgraph as pg
from PyQt6.QtCore import Qt, pyqtSignal
from PyQt6.QtGui import QCloseEvent, QResizeEvent
from PyQt6.QtWidgets import QHBoxLayout, QLabel, QPushButton, QVBoxLayout, QWidget

from engine.latent.solved_frames import SolvedFrames
from widgets.plots import CountAxis, fit_frames, release, settle

#: Readouts drawn, with their colours and legend names.
CURVES = (
    ("nearest", "#4da3ff", "nearest training latent"),
    ("norm", "#c77dff", "latent norm"),
    ("predictor", "#3fae55", "prior latent to solution"),
)
COLOURS = {k: c for k, c, _ in CURVES}
FLAG_COLOUR = "#ff3b30"


def consecutive(frames: np.ndarray) -> np.ndarray:
    """``connect`` for a curve over ``frames (F,)``: a line only between neighbouring
    frames, so a range never solved shows as a gap."""
    c = np.zeros(len(frames), bool)
    c[:-1] = np.diff(frames) == 1
    return c


class LatentReadouts(QWidget):
    """See the module doc. ``seekRequested(int)`` asks for a frame.

    Parameters
    ----------
    solved : SolvedFrames, optional
        The store to read and feed (the window shares one with the latent map).
    """

    seekRequested = pyqtSignal(int)
    flagsChanged = pyqtSignal(object)

    def __init__(self, parent: QWidget | None = None, solved: SolvedFrames | None = None) -> None:
        super().__init__(parent)
        self.solved = solved if solved is not None else SolvedFrames()
        layout = QVBoxLayout(self)
        layout.setContentsMargins(0, 0, 0, 0)
        row = QHBoxLayout()
        self.label = QLabel("")
        self.label.setTextFormat(Qt.TextFormat.RichText)
        self.label.setWordWrap(True)
        self.next_button = QPushButton("Next flagged frame")
        self.next_button.setToolTip(
            "Go to the next frame the flag rule marks (nearest training latent or norm above its threshold)"
        )
        self.next_button.clicked.connect(self._next)
        row.addWidget(self.label, 1)
        row.addWidget(self.next_button)
        layout.addLayout(row)
        self.plot = pg.PlotWidget(axisItems={"bottom": CountAxis("bottom")})
        self.plot.setMinimumHeight(120)
        self.plot.setLabel("bottom", "frame")
        # distances and the norm are all lengths in the VAE's latent space (docs/latent.md)
        self.plot.setLabel("left", "latent units")
        for side in ("bottom", "left"):
            self.plot.getAxis(side).enableAutoSIPrefix(False)
        self.plot.addLegend(offset=(4, 4), labelTextSize="7pt")
        self.curves = {k: self.plot.plot(pen=pg.mkPen(c, width=1), name=label) for k, c, label in CURVES}
        self.thresholds = {
            k: pg.InfiniteLine(
                angle=0,
                pen=pg.mkPen(COLOURS[k], width=1, style=Qt.PenStyle.DashLine),
                label=f"{k} flag",
                labelOpts={"position": 0.97, "color": COLOURS[k], "anchors": [(1, 0), (1, 0)]},
            )
            for k in ("nearest", "norm")
        }
        self.limits = {"nearest": float("inf"), "norm": float("inf")}
        for line in self.thresholds.values():
            line.setVisible(False)
            self.plot.addItem(line)
        self.flags = pg.ScatterPlotItem(size=9, symbol="x", pen=None, brush=FLAG_COLOUR)
        self.cursor = pg.InfiniteLine(angle=90, pen=pg.mkPen("#ffffff", width=1))
        self.plot.addItem(self.flags)
        self.plot.addItem(self.cursor)
        layout.addWidget(self.plot, 1)
        self.frame = 0
        self._flagged: list[int] = []
        self._version = -1  # the store's version whose flags were announced
        self._drawn = (-1, -1)  # (snapshot seq, store version) drawn

    def closeEvent(self, event: QCloseEvent | None) -> None:  # noqa: N802 (Qt's name)
        """A closed view holds no plot item (:func:`widgets.plots.release`)."""
        release(self.plot)
        super().closeEvent(event)

    def resizeEvent(self, event: QResizeEvent | None) -> None:  # noqa: N802 (Qt's name)
        super().resizeEvent(event)
        self._fit_label()

    def _fit_label(self) -> None:
        """Ask for the readout line's wrapped height: a splitter or dock reads only minimum
        sizes, not a wrapped label's height for its width, so two or three lines pushed the
        chart (its "frame" label first) past the bottom of the dock."""
        width = self.label.width()
        if width > 0:
            need = self.label.heightForWidth(width)
            if need > 0 and need != self.label.minimumHeight():
                self.label.setMinimumHeight(need)

    def mark_stale(self) -> None:
        """Draw the next snapshot even if it is the one drawn last (a view brought back
        into sight after it skipped snapshots)."""
        self._drawn = (-1, -1)

    def clear(self) -> None:
        """Forget the solved frames (another clip or method)."""
        self.solved.clear()
        self._flagged = []
        self.flagsChanged.emit([])
        self.next_button.setEnabled(False)
        for curve in self.curves.values():
            curve.setData([], [])
        self.flags.setData([], [])
        self.label.setText("")
        self._fit_label()

    def set_thresholds(self, nearest: float, norm: float) -> None:
        """The flag rule's thresholds, drawn dashed."""
        for key, value in (("nearest", nearest), ("norm", norm)):
            self.limits[key] = float(value)
            self.thresholds[key].setValue(float(value))
            self.thresholds[key].setVisible(bool(np.isfinite(value)))

    def note_verdicts(self, snap: Any) -> None:
        """Read ``snap``'s new solves into the store (cheap: only the history entries newer
        than the last one read); emits ``flagsChanged`` when the flagged set changes."""
        self.frame = int(snap.frame)
        self.solved.note(snap.history)
        if self.solved.version == self._version:  # the map may have read the store first
            return
        self._version = self.solved.version
        flagged = self.solved.flagged_frames
        if flagged != self._flagged:
            self._flagged = flagged
            self.flagsChanged.emit(flagged)
        self.next_button.setEnabled(bool(flagged))

    def update_snapshot(self, snap: Any) -> None:
        """:meth:`note_verdicts`, then draw every solved frame and the frame on screen."""
        self.note_verdicts(snap)
        if (snap.seq, self.solved.version) == self._drawn:
            return
        self._drawn = (snap.seq, self.solved.version)
        s = self.solved
        x = s.frames.astype(float)
        connect = consecutive(s.frames)
        for key, curve in self.curves.items():
            y = s.column(key)
            curve.setData(x, y, connect=connect) if np.isfinite(y).any() else curve.setData([], [])
        near, norm = s.column("nearest"), s.column("norm")
        on = s.flagged
        # the cross sits on the readout that crossed its threshold
        y = np.where(near > self.limits["nearest"], near, norm)
        on &= np.isfinite(y)
        self.flags.setData(x[on], y[on])
        self.cursor.setValue(float(snap.frame))
        self.label.setText(self.describe(snap))
        self._fit_label()
        fit_frames(self.plot, x)
        settle(self.plot)

    def describe(self, snap: Any) -> str:
        """The line above the chart: the frame on screen's readouts against the thresholds
        and its verdict (rich text)."""
        v = snap.latent_view
        if v is None:
            return str(snap.latent_note)
        near, norm = self.limits["nearest"], self.limits["norm"]

        def against(value: float, limit: float) -> str:
            if not np.isfinite(limit):
                return f"{value:.2f}"
            return f"{value:.2f} {'&gt;' if value > limit else '&le;'} {limit:.2f}"

        text = f"frame {v.frame}: nearest {against(v.nearest, near)}, norm {against(v.norm, norm)}, prior {v.predictor:.2f}"
        if v.flagged:
            return text + f" <b style='color:{FLAG_COLOUR}'>flagged</b>"
        earlier = self.solved.earlier_flag(v.frame)
        if earlier is not None:
            text += (
                f"<br><span style='color:{FLAG_COLOUR}'>flagged when solved before (nearest"
                f" {against(earlier['nearest'], near)}, norm {against(earlier['norm'], norm)});"
                " solved again from here it is not</span>"
            )
        return text

    def next_flagged(self) -> int | None:
        """The frame *Next flagged frame* goes to (None: none flagged)."""
        return self.solved.next_flagged(self.frame)

    def _next(self) -> None:
        frame = self.next_flagged()
        if frame is not None:
            self.seekRequested.emit(frame)
