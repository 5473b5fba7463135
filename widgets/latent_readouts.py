"""Prior readouts over the solved frames, with the flagged frames and a jump to the next.

Three curves over the engine's recent frames (``snap.history``): the distance to the
nearest training latent, the latent norm and the distance from the prior latent
(docs/latent.md), the flag thresholds dashed, flagged frames as red crosses. *Next
flagged frame* emits ``seekRequested(frame)`` for the first flagged frame after the one
on screen (wrapping to the first), among every frame solved since :meth:`clear` (the
engine's history restarts at each jump; this widget remembers the verdicts across them,
so the timeline can mark them: ``flagsChanged(frames)``).
"""

from __future__ import annotations

from typing import Any

import numpy as np
import pyqtgraph as pg
from PyQt6.QtCore import Qt, pyqtSignal
from PyQt6.QtWidgets import QHBoxLayout, QLabel, QPushButton, QVBoxLayout, QWidget

from engine.latent.readouts import next_flagged
from widgets.plots import fit_frames, settle

#: Readouts drawn, with their colours and legend names.
CURVES = (
    ("nearest", "#4da3ff", "nearest training latent"),
    ("norm", "#c77dff", "latent norm"),
    ("predictor", "#3fae55", "prior latent to solution"),
)
FLAG_COLOUR = "#ff3b30"


def _key(entry: Any) -> tuple:
    """What tells one solve's history entry from another's: the snapshots of an engine in
    its own process arrive unpickled, so the same entry is a new object every time."""
    return entry.frame, entry.ms, entry.iterations


class LatentReadouts(QWidget):
    """See the module doc. ``seekRequested(int)`` asks for a frame."""

    seekRequested = pyqtSignal(int)
    flagsChanged = pyqtSignal(object)

    def __init__(self, parent: QWidget | None = None) -> None:
        super().__init__(parent)
        layout = QVBoxLayout(self)
        layout.setContentsMargins(0, 0, 0, 0)
        row = QHBoxLayout()
        self.label = QLabel("")
        self.label.setTextFormat(Qt.TextFormat.RichText)
        self.next_button = QPushButton("Next flagged frame")
        self.next_button.setToolTip(
            "Go to the next frame the flag rule marks (nearest training latent or norm above its threshold)"
        )
        self.next_button.clicked.connect(self._next)
        row.addWidget(self.label, 1)
        row.addWidget(self.next_button)
        layout.addLayout(row)
        self.plot = pg.PlotWidget()
        self.plot.setMinimumHeight(120)
        self.plot.setLabel("bottom", "frame")
        self.plot.getAxis("bottom").enableAutoSIPrefix(False)
        self.plot.addLegend(offset=(4, 4), labelTextSize="7pt")
        self.curves = {k: self.plot.plot(pen=pg.mkPen(c, width=1), name=label) for k, c, label in CURVES}
        dash = pg.mkPen(FLAG_COLOUR, width=1, style=Qt.PenStyle.DashLine)
        self.thresholds = {k: pg.InfiniteLine(angle=0, pen=dash) for k in ("nearest", "norm")}
        for line in self.thresholds.values():
            line.setVisible(False)
            self.plot.addItem(line)
        self.flags = pg.ScatterPlotItem(size=9, symbol="x", pen=None, brush=FLAG_COLOUR)
        self.cursor = pg.InfiniteLine(angle=90, pen=pg.mkPen("#ffffff", width=1))
        self.plot.addItem(self.flags)
        self.plot.addItem(self.cursor)
        layout.addWidget(self.plot, 1)
        self.frames = np.zeros(0, int)
        self.flagged = np.zeros(0, bool)
        self.frame = 0
        self.verdicts: dict[int, bool] = {}  # frame -> flagged, every frame solved since clear()
        self._last_entry: Any = None  # the newest history entry read (its _key)
        self._seq = -1

    def clear(self) -> None:
        """Forget the verdicts (another clip or method)."""
        self.verdicts.clear()
        self._last_entry = None
        self.flagsChanged.emit([])

    def set_thresholds(self, nearest: float, norm: float) -> None:
        """The flag rule's thresholds, drawn dashed."""
        for key, value in (("nearest", nearest), ("norm", norm)):
            self.thresholds[key].setValue(float(value))
            self.thresholds[key].setVisible(bool(np.isfinite(value)))

    def note_verdicts(self, snap: Any) -> None:
        """Remember the flag verdicts of ``snap``'s solved frames (cheap: only the entries
        newer than the last one read; a frame solved again takes its new verdict); emits
        ``flagsChanged`` when the flagged set changes."""
        self.frame = int(snap.frame)
        new = []
        for r in reversed(snap.history):
            if _key(r) == self._last_entry:
                break
            if r.readouts:
                new.append((r.frame, r.readouts.get("flagged", 0.0) > 0))
        if snap.history:
            self._last_entry = _key(snap.history[-1])
        if not new:
            return
        before = {f for f, on in self.verdicts.items() if on}
        self.verdicts.update(reversed(new))  # oldest first: the newest verdict of a frame wins
        after = {f for f, on in self.verdicts.items() if on}
        if after != before:
            self.flagsChanged.emit(sorted(after))
        self.next_button.setEnabled(bool(after))

    def update_snapshot(self, snap: Any) -> None:
        """:meth:`note_verdicts`, then draw the readouts of ``snap.history``."""
        if snap.seq == self._seq:
            return
        self._seq = snap.seq
        self.note_verdicts(snap)
        rows = [r for r in snap.history if r.readouts]
        self.frames = np.array([r.frame for r in rows], int)
        x = self.frames.astype(float)
        for key, curve in self.curves.items():
            y = np.array([r.readouts.get(key, np.nan) for r in rows], float)
            curve.setData(x, y) if np.isfinite(y).any() else curve.setData([], [])
        self.flagged = np.array([r.readouts.get("flagged", 0.0) > 0 for r in rows], bool)
        near = np.array([r.readouts["nearest"] for r in rows], float)
        self.flags.setData(x[self.flagged], near[self.flagged])
        self.cursor.setValue(float(snap.frame))
        v = snap.latent_view
        if v is None:
            self.label.setText(snap.latent_note)
        else:
            flag = f" <b style='color:{FLAG_COLOUR}'>flagged</b>" if v.flagged else ""
            self.label.setText(
                f"frame {v.frame}: nearest {v.nearest:.2f}, norm {v.norm:.2f}, prior {v.predictor:.2f}{flag}"
            )
        fit_frames(self.plot, x)
        settle(self.plot)

    def next_flagged(self) -> int | None:
        """The frame *Next flagged frame* goes to (None: none flagged)."""
        frames = np.array(list(self.verdicts), int)
        return next_flagged(np.array(list(self.verdicts.values()), bool), frames, self.frame)

    def _next(self) -> None:
        frame = self.next_flagged()
        if frame is not None:
            self.seekRequested.emit(frame)
