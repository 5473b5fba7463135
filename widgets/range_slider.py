"""The timeline's scrub slider with a selectable frame range, drawn as a band.

A plain press or drag scrubs as any slider does. With Shift held, a click marks the
range from the current frame to the clicked one, and a drag marks the frames it sweeps;
a right click clears the range. The range is what Edit ▸ Re-solve range acts on. The
selected constraint's frame range, when it has one, is drawn along the top
(:func:`widgets.frame_range.paint_span`).
"""

from __future__ import annotations

from PyQt6.QtCore import QPoint, Qt, pyqtSignal
from PyQt6.QtGui import QColor, QMouseEvent, QPainter, QPaintEvent
from PyQt6.QtWidgets import QSlider, QStyle, QStyleOptionSlider, QWidget

from widgets.frame_range import Span, paint_span

#: A Shift-press that moves less than this (pixels) before release is a click.
DRAG_START_PX = 4


class RangeSlider(QSlider):
    """Horizontal slider with a frame range; ``selectionChanged(start, end)`` on each
    change (``(-1, -1)`` when cleared)."""

    selectionChanged = pyqtSignal(int, int)

    def __init__(self, parent: QWidget | None = None) -> None:
        super().__init__(Qt.Orientation.Horizontal, parent)
        self._selection: tuple[int, int] | None = None
        self._press: tuple[int, int] | None = None  # x (pixels) and frame of a Shift-press
        self._marks: tuple[int, ...] = ()  # frames drawn as red ticks (flagged by latent debugging)
        self._span: Span | None = None  # the selected constraint's frame range

    def set_span(self, span: Span | None) -> None:
        """Draw the selected constraint's range ``(start, end, blend_in, blend_out)`` along
        the top (None: none)."""
        if span != self._span:
            self._span = span
            self.update()

    def span(self) -> Span | None:
        return self._span

    def set_marks(self, frames: list[int] | tuple[int, ...]) -> None:
        """Draw ``frames`` as short red ticks under the groove (empty: none)."""
        marks = tuple(int(f) for f in frames)
        if marks != self._marks:
            self._marks = marks
            self.update()

    def marks(self) -> tuple[int, ...]:
        return self._marks

    # -- the range ---------------------------------------------------------------
    def selection(self) -> tuple[int, int] | None:
        """``(start, end)`` frames, inclusive, start <= end; None when nothing is selected."""
        return self._selection

    def set_selection(self, start: int | None, end: int | None = None) -> None:
        """Select ``start..end`` (clamped to the slider's range, either order); None clears."""
        if start is None or end is None or self.maximum() < self.minimum():
            new = None
        else:
            lo, hi = sorted((int(start), int(end)))
            new = (max(lo, self.minimum()), min(hi, self.maximum()))
        if new != self._selection:
            self._selection = new
            self.update()
            self.selectionChanged.emit(*(new if new is not None else (-1, -1)))

    def _track(self) -> tuple[int, int]:
        """Pixel x of the handle's centre at the first frame, and the pixels it travels."""
        opt = QStyleOptionSlider()
        self.initStyleOption(opt)
        style = self.style()
        groove = style.subControlRect(QStyle.ComplexControl.CC_Slider, opt, QStyle.SubControl.SC_SliderGroove, self)
        handle = style.subControlRect(QStyle.ComplexControl.CC_Slider, opt, QStyle.SubControl.SC_SliderHandle, self)
        return groove.x() + handle.width() // 2, max(groove.width() - handle.width(), 1)

    def frame_at(self, x: int) -> int:
        """The frame under horizontal pixel ``x`` (the handle's centre lands there)."""
        x0, span = self._track()
        return QStyle.sliderValueFromPosition(self.minimum(), self.maximum(), x - x0, span)

    def _x_of(self, frame: int) -> int:
        x0, span = self._track()
        return x0 + QStyle.sliderPositionFromValue(self.minimum(), self.maximum(), frame, span)

    # -- mouse -------------------------------------------------------------------
    def mousePressEvent(self, event: QMouseEvent | None) -> None:  # noqa: N802 (Qt's name)
        if event is None:
            return
        x = int(event.position().x())
        if event.button() == Qt.MouseButton.RightButton:
            self.set_selection(None)
            event.accept()
            return
        if event.button() == Qt.MouseButton.LeftButton and event.modifiers() & Qt.KeyboardModifier.ShiftModifier:
            frame = self.frame_at(x)
            self._press = (x, frame)
            self.set_selection(self.value(), frame)  # a click: from the current frame
            event.accept()
            return
        if event.button() == Qt.MouseButton.LeftButton:
            # a click on the groove jumps there (QSlider pages by 10); the handle is then
            # under the mouse, so the press goes on as a drag of it
            self.setValue(self.frame_at(x))
        super().mousePressEvent(event)

    def mouseMoveEvent(self, event: QMouseEvent | None) -> None:  # noqa: N802 (Qt's name)
        if event is None:
            return
        if self._press is not None:
            x = int(event.position().x())
            if abs(x - self._press[0]) >= DRAG_START_PX:  # a drag: the frames swept
                self.set_selection(self._press[1], self.frame_at(x))
            event.accept()
            return
        super().mouseMoveEvent(event)

    def mouseReleaseEvent(self, event: QMouseEvent | None) -> None:  # noqa: N802 (Qt's name)
        if event is not None and self._press is not None:
            self._press = None
            event.accept()
            return
        super().mouseReleaseEvent(event)

    # -- drawing -----------------------------------------------------------------
    def paintEvent(self, event: QPaintEvent | None) -> None:  # noqa: N802 (Qt's name)
        super().paintEvent(event)
        if self._span is not None:
            painter = QPainter(self)
            paint_span(painter, self._x_of, self._span, 0, 4)
            painter.end()
        if self._marks:
            painter = QPainter(self)
            painter.setPen(QColor(255, 59, 48))
            for f in self._marks:
                x = self._x_of(f)
                painter.drawLine(x, self.height() - 5, x, self.height() - 1)
            painter.end()
        if self._selection is None:
            return
        x0, x1 = self._x_of(self._selection[0]), self._x_of(self._selection[1])
        painter = QPainter(self)
        painter.setPen(QColor(255, 160, 40))
        painter.setBrush(QColor(255, 160, 40, 90))
        painter.drawRect(x0 - 2, 1, max(x1 - x0, 0) + 4, self.height() - 3)
        painter.end()

    def point_of(self, frame: int) -> QPoint:
        """Where ``frame`` is drawn (tests click there)."""
        return QPoint(self._x_of(frame), self.height() // 2)
