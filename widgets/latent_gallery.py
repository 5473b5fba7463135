"""The dimension gallery: what each latent dimension does to the body.

For the frame on screen (after *Inspect this frame*), each of the 24 dimensions decoded
at -2 sigma (blue), unchanged (grey) and +2 sigma (orange), drawn as small front views
side by side (six per row, each turned so its hips lie across the view),
with the three joints that move most marked (red) and the first named under the cell. With a joint
chosen, the five dimensions that move that joint most right here (the Jacobian's
largest norms) have their labels in yellow. A legend above the cells says so.

The labels keep their size in pixels while the cells shrink with the view: where a
label no longer fits between its neighbours and the row below, it is shortened to its
dimension (``d7``; its tooltip gives the whole), and hidden where even that does not fit.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import pyqtgraph as pg
from PyQt6.QtCore import Qt
from PyQt6.QtGui import QCloseEvent, QFont
from PyQt6.QtWidgets import QLabel, QVBoxLayout, QWidget

from engine import skeleton as sk
from widgets.plots import release

COLUMNS = 6
#: Cell size in metres (a body is ~1.8 m tall; under its feet, room for a one-line label
#: at the Latent map dock's size, ~470 x 330 pixels).
CELL_W, CELL_H = 1.6, 2.9
#: Height kept under the top of a cell's label for its two lines, metres (the view's range
#: is set with it: pyqtgraph fits the range to the lines only, and cut the last row's names).
LABEL_ROOM = 1.0
OFFSET_COLOURS = ("#4da3ff", "#8a93a6", "#ff8a1f")
INFLUENCE_COLOUR = "#ffd60a"
MARK_COLOUR = "#ff3b30"
#: Pixels kept clear between neighbouring labels and between a label and the row below.
LABEL_GAP_PX = 3.0
#: Where a cell's label starts, below the cell's origin (the root), metres.
LABEL_DROP = 1.05


def legend_html() -> str:
    """The gallery's legend: what each colour stands for (rich text)."""

    def c(colour: str, text: str) -> str:
        return f"<span style='color:{colour}'><b>{text}</b></span>"

    minus, zero, plus = OFFSET_COLOURS
    return (
        f"Each dimension d at {c(minus, '-2 sigma')}, {c(zero, 'unchanged')} and {c(plus, '+2 sigma')}; "
        f"{c(MARK_COLOUR, 'dots')}: the 3 joints it moves most (the first named under it; "
        f"where the cells are small, in the tooltip of its number); "
        f"{c(INFLUENCE_COLOUR, 'yellow name')}: among the 5 that move the chosen joint most"
    )


#: What the gallery says while it has nothing to draw.
EMPTY_HINT = (
    "Empty until <b>Inspect this frame</b> (Forces tab): the dimensions are drawn for the frame "
    "inspected, until the next solve (an edit, another frame)."
)

_BONES = [(j, p) for j, p in enumerate(sk.PARENTS) if p >= 0]


def front_view(poses: np.ndarray) -> np.ndarray:
    """``(..., 22, 2)`` front-view coordinates of world joints ``(..., 22, 3)``: the root
    at 0, turned about the vertical so the first pose's hip line runs along +x, then
    (x, z)."""
    p = np.asarray(poses, float)
    rel = p - p[..., :1, :]
    first = rel.reshape(-1, sk.NUM_JOINTS, 3)[0]
    left = first[sk.JOINT_INDEX["lhip"]] - first[sk.JOINT_INDEX["rhip"]]
    a = -np.arctan2(left[1], left[0])
    c, s = np.cos(a), np.sin(a)
    x = c * rel[..., 0] - s * rel[..., 1]
    return np.stack([x, rel[..., 2]], axis=-1)


class LatentGallery(QWidget):
    """See the module doc. Feed it :meth:`set_detail` with the snapshot's ``latent_detail``."""

    def __init__(self, parent: QWidget | None = None) -> None:
        super().__init__(parent)
        layout = QVBoxLayout(self)
        layout.setContentsMargins(0, 0, 0, 0)
        self.plot = pg.PlotWidget()
        self.plot.setAspectLocked(True)
        self.plot.hideAxis("bottom")
        self.plot.hideAxis("left")
        self.plot.setMenuEnabled(False)
        self.plot.setToolTip(
            "Each latent dimension at -2 sigma (blue), 0 (grey), +2 sigma (orange); "
            "under each: the joints it moves most"
        )
        self.lines = [self.plot.plot(pen=pg.mkPen(c, width=1.2), connect="pairs") for c in OFFSET_COLOURS]
        self.marks = pg.ScatterPlotItem(size=6, pen=None, brush=MARK_COLOUR)
        self.plot.addItem(self.marks)
        self.labels: list[pg.TextItem] = []
        self._font = QFont()
        self._font.setPointSize(7)
        self.legend = QLabel(legend_html())
        self.legend.setTextFormat(Qt.TextFormat.RichText)
        self.legend.setWordWrap(True)
        # without an inspection the cells are empty: a black plot would look broken
        self.hint = QLabel(EMPTY_HINT)
        self.hint.setWordWrap(True)
        layout.addWidget(self.legend)
        layout.addWidget(self.hint)
        layout.addWidget(self.plot, 1)
        self.detail: Any = None
        self.influential: list[int] = []
        #: Each label's full and short text, and the metres between a label's top and the
        #: highest point of the row below (set with the cells).
        self._texts: list[tuple[str, str]] = []
        self._room_below = CELL_H
        self.plot.getPlotItem().getViewBox().sigResized.connect(lambda *_: self._fit_labels())
        self.plot.getPlotItem().getViewBox().sigRangeChanged.connect(lambda *_: self._fit_labels())

    def closeEvent(self, event: QCloseEvent | None) -> None:  # noqa: N802 (Qt's name)
        """A closed view holds no plot item (:func:`widgets.plots.release`)."""
        self.labels = []
        release(self.plot)
        super().closeEvent(event)

    def set_detail(self, detail: Any) -> None:
        """Draw a :class:`~engine.studio.latent_views.LatentDetail` (None clears)."""
        if detail is self.detail:
            return
        self.detail = detail
        self.hint.setVisible(detail is None)
        for t in self.labels:
            self.plot.removeItem(t)
        self.labels = []
        self._texts = []
        if detail is None:
            for line in self.lines:
                line.setData([], [])
            self.marks.setData([], [])
            return
        sweep = np.asarray(detail.sweep, float)  # (L, 3, 22, 3)
        L = sweep.shape[0]
        influence = detail.influence
        self.influential = [] if influence is None else [int(i) for i in np.argsort(influence)[::-1][:5]]
        segs: list[list[np.ndarray]] = [[], [], []]
        marks = []
        for d in range(L):
            ox, oy = (d % COLUMNS) * CELL_W, -(d // COLUMNS) * CELL_H
            v = front_view(sweep[d]) + np.array([ox, oy])
            for k in range(3):
                segs[k].append(v[k][np.array(_BONES).ravel()])
            top = np.argsort(detail.motion[d])[::-1][:3]
            marks.append(v[2][top])
            colour = INFLUENCE_COLOUR if d in self.influential else "#c8ccd4"
            full = f"d{d}\n{sk.JOINT_NAMES[top[0]]}"
            text = pg.TextItem(full, color=colour, anchor=(0.5, 0))
            text.setFont(self._font)
            text.setToolTip(full.replace("\n", ": moves "))  # the whole label where it is shortened
            text.setPos(ox, oy - LABEL_DROP)  # under the feet (the root sits at the cell origin)
            self.plot.addItem(text)
            self.labels.append(text)
            self._texts.append((full, f"d{d}"))
        highest = max(float(front_view(sweep[d])[..., 1].max()) for d in range(L))
        self._room_below = CELL_H - LABEL_DROP - highest
        for k in range(3):
            pts = np.concatenate(segs[k])
            self.lines[k].setData(pts[:, 0], pts[:, 1], connect="pairs")
        m = np.concatenate(marks)
        self.marks.setData(m[:, 0], m[:, 1])
        lowest_label = min(t.pos().y() for t in self.labels)
        everything = np.concatenate([np.concatenate(segs[k]) for k in range(3)])
        self.plot.setRange(
            xRange=(float(everything[:, 0].min()), float(everything[:, 0].max())),
            yRange=(lowest_label - LABEL_ROOM, float(everything[:, 1].max())),
            padding=0.02,
        )
        self._fit_labels()

    def _fit_labels(self) -> None:
        """Each label in full where it fits its cell's width and the room above the row
        below at the view's present scale, else its dimension alone, else hidden."""
        if not self.labels:
            return
        px, py = self.plot.getPlotItem().getViewBox().viewPixelSize()  # metres per pixel
        if not (px > 0 and py > 0):
            return
        wide, tall = CELL_W / px - LABEL_GAP_PX, self._room_below / py - LABEL_GAP_PX
        for label, texts in zip(self.labels, self._texts, strict=True):
            for text in texts:
                label.setText(text)
                box = label.textItem.boundingRect()
                if box.width() <= wide and box.height() <= tall:
                    label.setVisible(True)
                    break
            else:
                label.setVisible(False)
