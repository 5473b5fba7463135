"""One legend for every loss plot: a scrollable list of the current terms beside them.

A legend drawn inside a plot covers the curves, and with 12+ terms (six trackers with
position and rotation, the temporal prior, constraints) it does not fit a short
plot at all. This list sits beside the plots, scrolls, and lists exactly the terms of
the current frame: a sensor removed by a preset change leaves it. Unticking a term hides
its curves in every plot, and it stays hidden when it comes back.
"""

from __future__ import annotations

from PyQt6.QtCore import Qt, pyqtSignal
from PyQt6.QtGui import QColor, QIcon, QPixmap
from PyQt6.QtWidgets import QListWidget, QListWidgetItem

from widgets import style

SWATCH_PX = 10


def _swatch(colour: str) -> QIcon:
    pix = QPixmap(SWATCH_PX, SWATCH_PX)
    pix.fill(QColor(colour))
    return QIcon(pix)


class TermLegend(QListWidget):
    """Signals ``visibilityChanged(name, visible)`` when the user ticks or unticks a term."""

    visibilityChanged = pyqtSignal(str, bool)

    def __init__(self) -> None:
        super().__init__()
        self.setToolTip("Loss terms of this frame: untick one to hide its curves")
        self.setMinimumWidth(150)
        self.setMaximumWidth(220)
        self.setUniformItemSizes(True)
        # the plots' dark background, so light swatches (the white total) stay visible
        self.setStyleSheet(f"QListWidget {{ background: {style.PLOT_BACKGROUND}; color: {style.PLOT_FOREGROUND}; }}")
        self.hidden: set[str] = set()
        self.terms: tuple[str, ...] = ()
        self._updating = False
        self.itemChanged.connect(self._changed)

    def set_terms(self, names: tuple[str, ...], colours: dict[str, str]) -> bool:
        """List ``names`` (in order) with their colours; True when the set changed.

        Rebuilds only when the term list changes, so a steady stream of frames costs nothing.
        """
        names = tuple(names)
        if names == self.terms:
            return False
        self._updating = True
        try:
            self.clear()
            for name in names:
                item = QListWidgetItem(_swatch(colours.get(name, "#ffffff")), name)
                item.setFlags(item.flags() | Qt.ItemFlag.ItemIsUserCheckable)
                item.setCheckState(Qt.CheckState.Unchecked if name in self.hidden else Qt.CheckState.Checked)
                self.addItem(item)
        finally:
            self._updating = False
        self.terms = names
        return True

    def visible(self, name: str) -> bool:
        return name not in self.hidden

    def _changed(self, item: QListWidgetItem) -> None:
        if self._updating:
            return
        name, on = item.text(), item.checkState() == Qt.CheckState.Checked
        (self.hidden.discard if on else self.hidden.add)(name)
        self.visibilityChanged.emit(name, on)
