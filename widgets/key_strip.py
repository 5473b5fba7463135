"""The key timeline of the pose window: the animation's keys, its length and rate, preview.

A frame ruler with a mark per key: a click or drag scrubs (the window shows the frame,
an in-between too), a key dragged along it moves to where it is dropped. Buttons add a
key at the current frame, delete the current key, move it to the frame in the box;
spin boxes set the length (frames) and the rate (fps); Play plays the bake from the
current frame (once, or looped with Loop) and Stop ends it. The selected constraint's
frame range is drawn along the bottom (:func:`widgets.frame_range.paint_span`). Every edit is a signal;
the window applies it and shows the result back with :meth:`KeyStrip.set_state`.
"""

from __future__ import annotations

from PyQt6.QtCore import QPointF, QRectF, Qt, pyqtSignal
from PyQt6.QtGui import QColor, QMouseEvent, QPainter, QPaintEvent, QPen, QPolygonF
from PyQt6.QtWidgets import (
    QCheckBox,
    QComboBox,
    QDoubleSpinBox,
    QHBoxLayout,
    QLabel,
    QPushButton,
    QSpinBox,
    QVBoxLayout,
    QWidget,
)

from widgets import style
from widgets.frame_range import Span, paint_span

MAX_FRAMES = 36000
#: Height of the frame ruler above the keys, pixels.
RULER_PX = 16
#: Space at either end, so the first and last frame's line and key are whole, pixels.
MARGIN_PX = 8
#: A press this close to a key's mark grabs the key, pixels.
KEY_GRAB_PX = 6
#: Least spacing of the ruler's numbers, pixels.
LABEL_PX = 40
#: In-between rules (``engine.authoring.keys.SCHEMES``; widgets do not import the engine's solver).
SCHEMES = ("cubic", "linear", "spherical")
#: The label's words after "frame N" (or "key N") for a pose edited and not keyed: short
#: enough for the label's fixed width with three-digit frames.
EDITED = " \N{MIDDLE DOT} unkeyed edit \N{EM DASH} K to key"
#: The label's fixed width holds this text (longer ones are elided, whole in the tooltip).
LABEL_WIDEST = "frame 00000 / 00000, 000 keys (key)"


class _FixedLabel(QLabel):
    """A one-line label whose width is set, not taken from its text: a text that does not
    fit is elided (``text()`` is whole), so a new text never moves the widgets beside it."""

    def paintEvent(self, event: QPaintEvent | None) -> None:  # noqa: N802 (Qt's name)
        rect = self.contentsRect()
        shown = self.fontMetrics().elidedText(self.text(), Qt.TextElideMode.ElideRight, rect.width())
        p = QPainter(self)
        style = self.style()
        if style is not None:
            flags = int(self.alignment().value) | Qt.TextFlag.TextSingleLine.value
            style.drawItemText(p, rect, flags, self.palette(), self.isEnabled(), shown, self.foregroundRole())
        p.end()


class _Strip(QWidget):
    """The key timeline: a frame ruler, keys as marks, the current frame as a line with a
    head. A press or drag off the keys scrubs (``scrubbed(frame)``); a key dragged to
    another frame and dropped there asks to move it (``keyDragged(from, to)``); a press
    on a key without moving selects its frame."""

    scrubbed = pyqtSignal(int)
    keyDragged = pyqtSignal(int, int)

    def __init__(self, parent: QWidget | None = None) -> None:
        super().__init__(parent)
        self.setMinimumHeight(RULER_PX + 28)
        self.setCursor(Qt.CursorShape.PointingHandCursor)
        self.setToolTip("Click or drag to scrub (in-betweens are shown); drag a key to move it")
        # a click here leaves the number field typed into beside it: the keys pressed next
        # (3 for the side view) are the window's, not digits of the animation's length
        self.setFocusPolicy(Qt.FocusPolicy.ClickFocus)
        self.frames, self.keys, self.current = 61, (), 0
        self.dragging: int | None = None  # the key held
        self.drop = 0  # where it would land
        self.span: Span | None = None  # the selected constraint's frame range

    def frame_at(self, x: float) -> int:
        span = max(1.0, self.width() - 1 - 2 * MARGIN_PX)
        return max(0, min(self.frames - 1, int(round((x - MARGIN_PX) / span * (self.frames - 1)))))

    def x_of(self, frame: int) -> float:
        return MARGIN_PX + frame / max(1, self.frames - 1) * max(1.0, self.width() - 1 - 2 * MARGIN_PX)

    def key_at(self, x: float) -> int | None:
        """The key whose mark is under pixel ``x``, the nearest one if several."""
        near = [(abs(self.x_of(k) - x), k) for k in self.keys if abs(self.x_of(k) - x) <= KEY_GRAB_PX]
        return min(near)[1] if near else None

    def mousePressEvent(self, event: QMouseEvent | None) -> None:  # noqa: N802 (Qt's name)
        if event is None or event.button() != Qt.MouseButton.LeftButton:
            return
        x = event.position().x()
        key = self.key_at(x)
        if key is not None:
            self.dragging = self.drop = key
            self.update()
        else:
            self.scrubbed.emit(self.frame_at(x))

    def mouseMoveEvent(self, event: QMouseEvent | None) -> None:  # noqa: N802 (Qt's name)
        if event is None or not event.buttons() & Qt.MouseButton.LeftButton:
            return
        frame = self.frame_at(event.position().x())
        if self.dragging is not None:
            if frame != self.drop:
                self.drop = frame
                self.update()
        elif frame != self.current:
            self.scrubbed.emit(frame)

    def mouseReleaseEvent(self, event: QMouseEvent | None) -> None:  # noqa: N802 (Qt's name)
        if self.dragging is None:
            return
        key, drop, self.dragging = self.dragging, self.drop, None
        self.update()
        if drop != key:
            self.keyDragged.emit(key, drop)
        else:
            self.scrubbed.emit(key)

    def ruler_step(self) -> int:
        """Frames between numbered ticks: the smallest of 1, 2, 5, 10, 20, 50... that
        leaves :data:`LABEL_PX` pixels between numbers."""
        per_frame = max(1e-6, (self.width() - 2 * MARGIN_PX) / max(1, self.frames - 1))
        step, k = 1, 0
        while step * per_frame < LABEL_PX:
            k += 1
            step = (1, 2, 5)[k % 3] * 10 ** (k // 3)
        return step

    def paintEvent(self, event: QPaintEvent | None) -> None:  # noqa: N802 (Qt's name)
        p = QPainter(self)
        h = self.height()
        p.fillRect(self.rect(), QColor(style.PLOT_BACKGROUND))
        p.fillRect(QRectF(0, 0, self.width(), RULER_PX), QColor("#232733"))
        p.setPen(QColor(style.PLOT_FOREGROUND))
        font = p.font()
        font.setPixelSize(10)
        p.setFont(font)
        step = self.ruler_step()
        for f in range(0, self.frames, step):
            x = self.x_of(f)
            p.drawLine(QPointF(x, RULER_PX - 5), QPointF(x, RULER_PX))
            if x + 2 + p.fontMetrics().horizontalAdvance(str(f)) < self.width():  # no cut number at the end
                p.drawText(QPointF(x + 2, RULER_PX - 5), str(f))
        p.setPen(QColor("#3a4150"))
        for f in range(0, self.frames, max(1, step // 5)):
            x = self.x_of(f)
            p.drawLine(QPointF(x, RULER_PX), QPointF(x, RULER_PX + 3))
        for k in self.keys:
            ghost = self.dragging == k
            colour = QColor(style.GIZMO)
            if ghost:
                colour.setAlpha(90)
            self._diamond(p, self.x_of(k), colour)
        if self.dragging is not None:
            self._diamond(p, self.x_of(self.drop), QColor(style.GIZMO))
        if self.span is not None:
            paint_span(p, self.x_of, self.span, h - 5, 4)
        x = self.x_of(self.current)
        p.setPen(QPen(QColor(style.RECONSTRUCTION), 2))
        p.drawLine(QPointF(x, RULER_PX), QPointF(x, h))
        p.setBrush(QColor(style.RECONSTRUCTION))
        p.drawPolygon(QPolygonF([QPointF(x - 5, 0), QPointF(x + 5, 0), QPointF(x, 7)]))
        p.end()

    def _diamond(self, p: QPainter, x: float, colour: QColor) -> None:
        y, r = RULER_PX + (self.height() - RULER_PX) / 2, KEY_GRAB_PX - 1
        p.setPen(QColor(style.PLOT_BACKGROUND))
        p.setBrush(colour)
        p.drawPolygon(QPolygonF([QPointF(x, y - r - 2), QPointF(x + r, y), QPointF(x, y + r + 2), QPointF(x - r, y)]))


class KeyStrip(QWidget):
    """Signals: ``frameChanged(int)``, ``addRequested(int)``, ``deleteRequested(int)``,
    ``moveRequested(int, int)`` (from, to), ``lengthChanged(int)``, ``fpsChanged(float)``,
    ``interpolationChanged(str)``, ``previewRequested()``."""

    frameChanged = pyqtSignal(int)
    addRequested = pyqtSignal(int)
    deleteRequested = pyqtSignal(int)
    moveRequested = pyqtSignal(int, int)
    lengthChanged = pyqtSignal(int)
    fpsChanged = pyqtSignal(float)
    interpolationChanged = pyqtSignal(str)
    previewRequested = pyqtSignal()

    def __init__(self, parent: QWidget | None = None) -> None:
        super().__init__(parent)
        outer = QVBoxLayout(self)
        outer.setContentsMargins(4, 2, 4, 2)
        self.strip = _Strip()
        self.strip.scrubbed.connect(self._pick)
        self.strip.keyDragged.connect(self.moveRequested.emit)
        outer.addWidget(self.strip)
        row = QHBoxLayout()
        outer.addLayout(row)
        self.label = _FixedLabel()
        self.add = QPushButton("Add key")
        self.add.clicked.connect(lambda: self.addRequested.emit(self.strip.current))
        self.delete = QPushButton("Delete key")
        self.delete.clicked.connect(lambda: self.deleteRequested.emit(self.strip.current))
        self.move_to = QSpinBox(minimum=0, maximum=MAX_FRAMES - 1, prefix="to ")
        self.move = QPushButton("Move key")
        self.move.clicked.connect(lambda: self.moveRequested.emit(self.strip.current, self.move_to.value()))
        # the length and the rate are taken when typing ends (Return, focus out, the
        # arrows): taken at every digit, 200 typed would make the animation 2, 20 and
        # 200 frames long, three undo steps
        self.length = QSpinBox(minimum=1, maximum=MAX_FRAMES, suffix=" frames", keyboardTracking=False)
        self.length.valueChanged.connect(lambda v: self.lengthChanged.emit(int(v)))
        self.fps = QDoubleSpinBox(minimum=1.0, maximum=240.0, decimals=1, suffix=" fps", keyboardTracking=False)
        self.fps.valueChanged.connect(lambda v: self.fpsChanged.emit(float(v)))
        self.interpolation = QComboBox()
        self.interpolation.addItems(SCHEMES)
        self.interpolation.setToolTip("How in-betweens blend the keys' latents")
        self.interpolation.currentTextChanged.connect(self.interpolationChanged.emit)
        self.preview = QPushButton("Play")
        self.preview.setToolTip("Play the bake from the current frame; Stop ends it (Space)")
        self.preview.clicked.connect(self.previewRequested.emit)
        self.loop = QCheckBox("Loop")
        self.loop.setToolTip("Play again from the first frame at the end")
        self.edited: int | None = None  # the frame whose pose holds an edit not keyed
        # a width of its own: a label sized by its text would move every button after it
        # whenever the text changes (17 px for the unkeyed-edit text in a 1500 px window);
        # no wider than the row's least width allows, so neither the window nor the 3D view grows
        self.label.setFixedWidth(self.label.fontMetrics().horizontalAdvance(LABEL_WIDEST))
        for w in (
            self.label,
            self.add,
            self.delete,
            self.move_to,
            self.move,
            self.length,
            self.fps,
            self.interpolation,
            self.preview,
            self.loop,
        ):
            row.addWidget(w)
        self.set_state(61, 30.0, (), 0)

    def _pick(self, frame: int) -> None:
        self.set_state(self.strip.frames, self.fps.value(), self.strip.keys, frame)
        self.frameChanged.emit(frame)

    def set_state(
        self, frames: int, fps: float, keys: tuple[int, ...], current: int, interpolation: str | None = None
    ) -> None:
        """Show the animation without emitting signals."""
        if interpolation is not None:
            self.interpolation.blockSignals(True)
            self.interpolation.setCurrentText(interpolation)
            self.interpolation.blockSignals(False)
        s = self.strip
        before = s.current
        s.frames, s.keys, s.current = int(frames), tuple(sorted(keys)), max(0, min(int(current), int(frames) - 1))
        for w, v in ((self.length, int(frames)), (self.fps, float(fps))):
            w.blockSignals(True)
            w.setValue(v)
            w.blockSignals(False)
        self.move_to.setMaximum(max(0, int(frames) - 1))
        if s.current != before:
            # the box starts at the frame shown: Move key untouched moves nothing
            self.move_to.setValue(s.current)
        on_key = s.current in s.keys
        self.delete.setEnabled(on_key)
        self.move.setEnabled(on_key)
        self._show_label()
        s.update()

    def set_edited(self, frame: int | None) -> None:
        """Say that the pose at ``frame`` holds an edit it does not keep (None: no such edit)."""
        if frame != self.edited:
            self.edited = frame
            self._show_label()

    def _show_label(self) -> None:
        s = self.strip
        on_key = s.current in s.keys
        edited = s.current == self.edited
        self.label.setStyleSheet(f"color: {style.RECONSTRUCTION}" if edited else "")
        if edited:
            # leaving drops the edit: the label says so before, not the status bar after
            text = f"{'key' if on_key else 'frame'} {s.current}{EDITED}"
            self.label.setText(text)
            what = f"The key at frame {s.current} holds another pose" if on_key else "The pose shown here is edited"
            self.label.setToolTip(
                f"{text}\n{what}: K keys this pose; another frame does not keep it (Ctrl+Z there brings it back)"
            )
            return
        inside = len(s.keys) > 1 and s.keys[0] < s.current < s.keys[-1]
        where = " (key)" if on_key else " (in-between)" if inside else ""
        n = len(s.keys)
        self.label.setText(f"frame {s.current} / {s.frames - 1}, {n} key{'s' * (n != 1)}{where}")
        self.label.setToolTip(self.label.text())

    def set_constraint_span(self, span: Span | None) -> None:
        """Show the selected constraint's frame range ``(start, end, blend_in, blend_out)``
        under the keys (None: it acts on every frame, or none is selected)."""
        if span != self.strip.span:
            self.strip.span = span
            self.strip.update()

    def set_playing(self, playing: bool) -> None:
        """Show the Play button as Stop while the bake plays."""
        self.preview.setText("Stop" if playing else "Play")
