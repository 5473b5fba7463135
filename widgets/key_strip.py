"""The key strip under the timeline: the animation's keys, its length and rate, preview.

A strip of frames with a mark per key; clicking a frame makes it current. Buttons add a
key at the current frame, delete the current key, move it to another frame; spin boxes
set the length (frames) and the rate (fps). Every edit is a signal; the window applies
it and shows the result back with :meth:`KeyStrip.set_state`.
"""

from __future__ import annotations

from PyQt6.QtCore import QRectF, pyqtSignal
from PyQt6.QtGui import QColor, QMouseEvent, QPainter, QPaintEvent
from PyQt6.QtWidgets import (
    QComboBox, QDoubleSpinBox, QHBoxLayout, QLabel, QPushButton, QSpinBox, QVBoxLayout, QWidget,
)  # fmt: skip

from widgets import style

MAX_FRAMES = 36000
#: In-between rules (``engine.authoring.keys.SCHEMES``; widgets do not import the engine's solver).
SCHEMES = ("cubic", "linear", "spherical")


class _Strip(QWidget):
    """Frames as a bar, keys as marks, the current frame as a line."""

    clicked = pyqtSignal(int)

    def __init__(self, parent: QWidget | None = None) -> None:
        super().__init__(parent)
        self.setMinimumHeight(22)
        self.frames, self.keys, self.current = 61, (), 0

    def frame_at(self, x: float) -> int:
        return max(0, min(self.frames - 1, int(round(x / max(1, self.width() - 1) * (self.frames - 1)))))

    def x_of(self, frame: int) -> float:
        return frame / max(1, self.frames - 1) * (self.width() - 1)

    def mousePressEvent(self, event: QMouseEvent | None) -> None:
        if event is not None:
            self.clicked.emit(self.frame_at(event.position().x()))

    def paintEvent(self, event: QPaintEvent | None) -> None:
        p = QPainter(self)
        p.fillRect(self.rect(), QColor(style.PLOT_BACKGROUND))
        p.setPen(QColor(style.GIZMO))
        p.setBrush(QColor(style.GIZMO))
        for k in self.keys:
            x = self.x_of(k)
            p.drawRect(QRectF(x - 3, 3, 6, self.height() - 6))
        p.setPen(QColor(style.RECONSTRUCTION))
        x = self.x_of(self.current)
        p.drawLine(int(x), 0, int(x), self.height())
        p.end()


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
        self.strip.clicked.connect(self._pick)
        outer.addWidget(self.strip)
        row = QHBoxLayout()
        outer.addLayout(row)
        self.label = QLabel()
        self.add = QPushButton("Add key")
        self.add.clicked.connect(lambda: self.addRequested.emit(self.strip.current))
        self.delete = QPushButton("Delete key")
        self.delete.clicked.connect(lambda: self.deleteRequested.emit(self.strip.current))
        self.move_to = QSpinBox(minimum=0, maximum=MAX_FRAMES - 1, prefix="to ")
        self.move = QPushButton("Move key")
        self.move.clicked.connect(lambda: self.moveRequested.emit(self.strip.current, self.move_to.value()))
        self.length = QSpinBox(minimum=1, maximum=MAX_FRAMES, suffix=" frames")
        self.length.valueChanged.connect(lambda v: self.lengthChanged.emit(int(v)))
        self.fps = QDoubleSpinBox(minimum=1.0, maximum=240.0, decimals=1, suffix=" fps")
        self.fps.valueChanged.connect(lambda v: self.fpsChanged.emit(float(v)))
        self.interpolation = QComboBox()
        self.interpolation.addItems(SCHEMES)
        self.interpolation.setToolTip("How in-betweens blend the keys' latents")
        self.interpolation.currentTextChanged.connect(self.interpolationChanged.emit)
        self.preview = QPushButton("Preview")
        self.preview.clicked.connect(self.previewRequested.emit)
        for w in (self.label, self.add, self.delete, self.move_to, self.move, self.length, self.fps, self.interpolation,
                  self.preview):  # fmt: skip
            row.addWidget(w)
        self.set_state(61, 30.0, (), 0)

    def _pick(self, frame: int) -> None:
        self.set_state(self.strip.frames, self.fps.value(), self.strip.keys, frame)
        self.frameChanged.emit(frame)

    def set_state(self, frames: int, fps: float, keys: tuple[int, ...], current: int,
                  interpolation: str | None = None) -> None:  # fmt: skip
        """Show the animation without emitting signals."""
        if interpolation is not None:
            self.interpolation.blockSignals(True)
            self.interpolation.setCurrentText(interpolation)
            self.interpolation.blockSignals(False)
        s = self.strip
        s.frames, s.keys, s.current = int(frames), tuple(sorted(keys)), max(0, min(int(current), int(frames) - 1))
        for w, v in ((self.length, int(frames)), (self.fps, float(fps))):
            w.blockSignals(True)
            w.setValue(v)
            w.blockSignals(False)
        self.move_to.setMaximum(max(0, int(frames) - 1))
        on_key = s.current in s.keys
        self.delete.setEnabled(on_key)
        self.move.setEnabled(on_key)
        self.label.setText(f"frame {s.current} / {frames - 1}, {len(s.keys)} key{'s' * (len(s.keys) != 1)}")
        s.update()
