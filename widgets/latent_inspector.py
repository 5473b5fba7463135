"""Latent inspector: the current latent vector, its history, and a decoding debugger.

Debug mode pauses playback; then one latent dimension can be scrubbed, or two stored
latents (A and B, captured from any frames) interpolated, and each change asks the
engine to decode the edited latent (``decodeRequested``). Methods without a decoder
leave the debugger disabled, with a tooltip saying why.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import pyqtgraph as pg
from PyQt6.QtCore import QRectF, Qt, pyqtSignal
from PyQt6.QtGui import QCloseEvent
from PyQt6.QtWidgets import QCheckBox, QGridLayout, QLabel, QPushButton, QSlider, QSpinBox, QVBoxLayout, QWidget

from widgets.plots import release, settle  # also applies the shared pyqtgraph look

HISTORY = 300
#: the smallest half range of the bars' y axis and of the strip's colour levels
MIN_RANGE = 1e-6
NO_DECODER = "The current method has no latent decoder (choose dragposer when it is available)."


class LatentInspector(QWidget):
    """Signals ``decodeRequested(ndarray)`` and ``debugToggled(bool)``."""

    decodeRequested = pyqtSignal(object)
    debugToggled = pyqtSignal(bool)

    def __init__(self, parent: QWidget | None = None) -> None:
        super().__init__(parent)
        layout = QVBoxLayout(self)
        layout.setContentsMargins(0, 0, 0, 0)
        # no title either: at the studio's size its ~25 px left the bars ~40 px, too few
        # for three y labels; the dock says "Latent", the strip below is the history
        self.bars_plot = pg.PlotWidget()
        self.bars_plot.setMinimumHeight(90)
        self.bars_plot.setToolTip("This frame's latent: one bar per dimension (orange > 0, blue <= 0)")
        self.bars = pg.BarGraphItem(x=np.arange(24), height=np.zeros(24), width=0.8, brush="#4da3ff")
        self.bars_plot.addItem(self.bars)
        # no title (its ~25 px go to the image): the axes say what it shows; at least
        # ~4 px per dimension so 24 rows stay readable
        self.strip_plot = pg.PlotWidget()
        self.strip_plot.setMinimumHeight(150)
        self.strip_plot.setLabel("bottom", "frame")
        self.strip_plot.setLabel("left", "latent dim")
        self.strip_plot.setToolTip("Latent history: one row per dimension, one column per solved frame")
        self.strip_plot.getAxis("bottom").enableAutoSIPrefix(False)
        self.strip = pg.ImageItem()
        self.strip.setColorMap(pg.colormap.get("CET-D1"))
        self.strip_plot.addItem(self.strip)
        self.placeholder = QLabel("This method has no latent space (DragPoser's is 24-D).")
        self.placeholder.setAlignment(Qt.AlignmentFlag.AlignCenter)
        self.placeholder.setStyleSheet("color: #8a93a6;")
        layout.addWidget(self.placeholder)
        layout.addWidget(self.bars_plot, 2)
        layout.addWidget(self.strip_plot, 3)
        self._show_plots(False)
        self.debug_box = QWidget()
        grid = QGridLayout(self.debug_box)
        self.debug = QCheckBox("Debug: pause optimizer and decode edited latents")
        self.debug.toggled.connect(self._debug_toggled)
        self.dim = QSpinBox(minimum=0, maximum=23, prefix="dim ")
        self.value = QSlider(Qt.Orientation.Horizontal, minimum=-300, maximum=300, toolTip="value x 100")
        self.value.valueChanged.connect(self._scrub)
        self.value_label = QLabel("0.00")
        self.value_label.setMinimumWidth(self.value_label.fontMetrics().horizontalAdvance("-3.00") + 6)
        self.dim.valueChanged.connect(self._dim_chosen)
        #: The latent being decoded in debug mode (the bars show it), None otherwise.
        self.edited: np.ndarray | None = None
        self.capture_a = QPushButton("Store as A")
        self.capture_b = QPushButton("Store as B")
        self.capture_a.clicked.connect(lambda: self._store("a"))
        self.capture_b.clicked.connect(lambda: self._store("b"))
        self.mix = QSlider(Qt.Orientation.Horizontal, minimum=0, maximum=100, toolTip="A to B")
        self.mix.valueChanged.connect(self._interpolate)
        grid.addWidget(self.debug, 0, 0, 1, 4)
        grid.addWidget(self.dim, 1, 0)
        grid.addWidget(self.value, 1, 1, 1, 2)
        grid.addWidget(self.value_label, 1, 3)
        grid.addWidget(self.capture_a, 2, 0)
        grid.addWidget(self.capture_b, 2, 1)
        grid.addWidget(QLabel("A → B"), 2, 2)
        grid.addWidget(self.mix, 2, 3)
        layout.addWidget(self.debug_box)
        self.set_decodable(False)
        self.latent: np.ndarray | None = None
        self.stored: dict[str, np.ndarray] = {}
        self._seq = -1
        self._frame: int | None = None  # the frame of the latent shown (an edit belongs to it)
        self._bars_range = 0.0

    def closeEvent(self, event: QCloseEvent | None) -> None:  # noqa: N802 (Qt's name)
        """Take the bars and the strip out of their plots and drop the strip's image: a
        closed view holds no plot item (:func:`widgets.plots.release`)."""
        release(self.bars_plot, self.strip_plot)
        self.strip.clear()
        super().closeEvent(event)

    def _show_plots(self, on: bool) -> None:
        self.placeholder.setVisible(not on)
        self.bars_plot.setVisible(on)
        self.strip_plot.setVisible(on)

    def set_decodable(self, ok: bool) -> None:
        self.debug_box.setEnabled(ok)
        self.debug_box.setToolTip("" if ok else NO_DECODER)
        if not ok and self.debug.isChecked():
            self.debug.setChecked(False)

    def update_snapshot(self, snap: Any) -> None:
        if snap.seq == self._seq:
            return
        self._seq = snap.seq
        if self.debug_box.isEnabled() != bool(snap.can_decode):
            self.set_decodable(bool(snap.can_decode))
        if (snap.latent is not None) != self.bars_plot.isVisible():
            self._show_plots(snap.latent is not None)
        if snap.latent is None:
            return
        z = np.asarray(snap.latent, float).ravel()
        # in debug mode too: after a seek, "Store as B" stores the new frame's latent; the
        # engine's latent is unchanged by decoding requests, and an edit made on another
        # frame is dropped
        self.latent = z
        if snap.frame != self._frame:
            self._frame, self.edited = snap.frame, None
        self._draw_bars(z if self.edited is None or self.edited.size != z.size else self.edited)
        # the engine's record covers frames this view never drew (it draws the newest only)
        recorded = [r for r in snap.history[-HISTORY:] if r.latent is not None and np.size(r.latent) == z.size]
        image, lim = strip_image([np.ravel(r.latent) for r in recorded] or [z])
        frames = [r.frame for r in recorded] or [snap.frame]
        self.strip.setImage(image, levels=(-lim, lim))
        # x in clip frames, like the other history plots (a slow solver skips frames, so
        # the rows are not one per frame)
        span = max(frames[-1] - frames[0], 1)
        self.strip.setRect(QRectF(frames[0], 0.0, span, image.shape[1]))
        settle(self.bars_plot)
        settle(self.strip_plot)

    def _draw_bars(self, z: np.ndarray) -> None:
        """This frame's latent as bars on a symmetric y axis labelled -m, 0, m only.

        pyqtgraph's own ticks put four labels (0.5 / 0 / -0.5 / -1.0) on the ~45 px the
        plot has in the studio, one touching the next. The half range m steps through
        1, 2, 5 x 10^k, so the axis does not change with every frame.
        """
        # a diverged solve's NaN/inf would make a bar without a rectangle: none is drawn
        height = np.where(np.isfinite(z), z, 0.0)
        brushes = ["#ff8a1f" if v > 0 else "#4da3ff" for v in height]
        self.bars.setOpts(x=np.arange(len(z)), height=height, brushes=brushes)
        m = nice_ceil(float(np.abs(height).max(initial=0.0)))
        if m != self._bars_range:
            self._bars_range = m
            self.bars_plot.setYRange(-m, m, padding=0.15)  # room for the end labels
            self.bars_plot.getAxis("left").setTicks([[(v, f"{v:g}") for v in (-m, 0.0, m)]])

    def _debug_toggled(self, on: bool) -> None:
        self.debugToggled.emit(on)
        self.edited = None
        if on and self.latent is not None:
            self._dim_chosen(self.dim.value())
            self._decode(self.latent.copy())  # starts on the pose on screen
        elif self.latent is not None:
            self._draw_bars(self.latent)

    def _dim_chosen(self, dim: int) -> None:
        """The value slider shows the chosen dimension's value (of the edited latent)."""
        z = self.edited if self.edited is not None else self.latent
        if z is not None and 0 <= dim < z.size:
            self.value.blockSignals(True)
            self.value.setValue(int(round(float(z[dim]) * 100)))
            self.value.blockSignals(False)
            self.value_label.setText(f"{float(z[dim]):.2f}")

    def _decode(self, z: np.ndarray) -> None:
        self.edited = z
        self._draw_bars(z)
        self.decodeRequested.emit(z)

    def _scrub(self, v: int) -> None:
        self.value_label.setText(f"{v / 100.0:.2f}")
        if self.debug.isChecked() and self.latent is not None:
            z = (self.edited if self.edited is not None else self.latent).copy()
            z[self.dim.value()] = v / 100.0
            self._decode(z)

    def _store(self, slot: str) -> None:
        """Store the latent shown: the one being edited (scrubbed or blended), else the
        frame's solved latent."""
        z = self.edited if self.edited is not None else self.latent
        if z is not None:
            self.stored[slot] = z.copy()

    def _interpolate(self, v: int) -> None:
        if self.debug.isChecked() and {"a", "b"} <= set(self.stored):
            t = v / 100.0
            self._decode((1 - t) * self.stored["a"] + t * self.stored["b"])


def nice_ceil(x: float) -> float:
    """The smallest of 1, 2, 5 x 10^k that is >= ``x`` (at least :data:`MIN_RANGE`)."""
    x = max(x, MIN_RANGE)
    base = 10.0 ** np.floor(np.log10(x))
    return next(float(f * base) for f in (1, 2, 5, 10) if f * base >= x * (1 - 1e-12))


def strip_image(rows: list[np.ndarray]) -> tuple[np.ndarray, float]:
    """The latent history as the strip's pixels, and the half range of its colour levels.

    Parameters
    ----------
    rows : list of ndarray (L,)
        One latent per solved frame, oldest first.

    Returns
    -------
    image : ndarray (F, L) float64
        A new C-contiguous array that nobody else holds, made read-only: pyqtgraph keeps
        it and renders from it whenever the plot repaints, so it must never change after
        ``setImage``. NaN is 0 (the map's neutral middle) and +-inf saturate, so pyqtgraph
        never takes its NaN path nor scales by a non-finite level.
    lim : float
        Largest finite magnitude (at least :data:`MIN_RANGE`); levels are ``(-lim, lim)``.
    """
    image = np.array(rows, dtype=np.float64, order="C")  # always a copy
    finite = np.isfinite(image)
    lim = max(float(np.abs(image[finite]).max(initial=0.0)), MIN_RANGE)
    image[np.isnan(image)] = 0.0
    np.clip(image, -lim, lim, out=image)
    image.flags.writeable = False
    return image, lim
