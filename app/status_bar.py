"""A status bar whose message is read whole: never under a readout, elided when too wide.

QStatusBar hides its normal widgets (the studio's solver and view readouts) for a
message only if they are visible at that moment: a message shown before the window is
on screen ("Starting ...", "Loaded FILE") is then drawn under readouts that appear with
the window. It also clips a message wider than the bar mid-glyph, with no way to read
the rest. This bar hides its readouts whenever a message shows, whatever the window's
state, and draws a too-wide message elided, its whole text in the bar's tooltip.
"""

from __future__ import annotations

from PyQt6.QtCore import QRect, Qt
from PyQt6.QtGui import QPainter, QPaintEvent, QResizeEvent
from PyQt6.QtWidgets import QSizeGrip, QStatusBar, QStyle, QStyleOption, QWidget


class StatusBar(QStatusBar):
    """:class:`QStatusBar` with readouts that give way to every message, and elided messages."""

    def __init__(self, parent: QWidget | None = None) -> None:
        super().__init__(parent)
        self._readouts: list[QWidget] = []  # addWidget's: hidden while a message shows
        self._permanent: list[QWidget] = []  # addPermanentWidget's: always shown, at the right
        self.messageChanged.connect(self._on_message)

    def addWidget(self, widget: QWidget | None, stretch: int = 0) -> None:  # noqa: N802 (Qt's name)
        """Add a readout on the left; hidden while a message shows."""
        super().addWidget(widget, stretch)
        if widget is not None:
            self._readouts.append(widget)
            widget.setVisible(not self.currentMessage())

    def addPermanentWidget(self, widget: QWidget | None, stretch: int = 0) -> None:  # noqa: N802 (Qt's name)
        """Add a widget on the right, shown beside messages."""
        super().addPermanentWidget(widget, stretch)
        if widget is not None:
            self._permanent.append(widget)

    def message_rect(self) -> QRect:
        """Where the message is drawn (pixels, the bar's coordinates): up to the permanent widgets."""
        right = self.width() - 12
        grips = [g for g in self.findChildren(QSizeGrip) if g.parent() is self and g.isVisible()]
        if grips:
            right = grips[0].x()
        shown = [w.x() - 2 for w in self._permanent if w.isVisible()]
        if shown:
            right = min(right, *shown)
        return QRect(6, 0, max(0, right - 6), self.height())

    def shown_message(self) -> str:
        """The message as drawn: whole, or elided at the right to fit :meth:`message_rect`."""
        return self.fontMetrics().elidedText(
            self.currentMessage(), Qt.TextElideMode.ElideRight, self.message_rect().width()
        )

    def _on_message(self, message: str) -> None:
        for w in self._readouts:
            w.setVisible(not message)
        self._update_tip()

    def _update_tip(self) -> None:
        message = self.currentMessage()
        self.setToolTip(message if message and self.shown_message() != message else "")

    def resizeEvent(self, event: QResizeEvent | None) -> None:  # noqa: N802 (Qt's name)
        super().resizeEvent(event)
        self._update_tip()

    def paintEvent(self, event: QPaintEvent | None) -> None:  # noqa: N802 (Qt's name)
        """QStatusBar's own painting, with the message elided instead of clipped."""
        painter = QPainter(self)
        style = self.style()
        assert style is not None
        option = QStyleOption()
        option.initFrom(self)
        style.drawPrimitive(QStyle.PrimitiveElement.PE_PanelStatusBar, option, painter, self)
        for w in self._readouts + self._permanent:
            if w.isVisible():
                frame = QStyleOption()
                frame.rect = w.geometry().adjusted(-2, -1, 2, 1)
                frame.palette = self.palette()
                style.drawPrimitive(QStyle.PrimitiveElement.PE_FrameStatusBarItem, frame, painter, w)
        if self.currentMessage():
            painter.setPen(self.palette().windowText().color())
            flags = Qt.AlignmentFlag.AlignLeading.value | Qt.AlignmentFlag.AlignVCenter.value
            painter.drawText(self.message_rect(), flags | Qt.TextFlag.TextSingleLine.value, self.shown_message())
        painter.end()
