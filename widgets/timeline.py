"""Timeline: play/pause, step, scrub, a selectable frame range, speed, loop, playback pace
and a frame counter."""

from __future__ import annotations

from PyQt6.QtCore import Qt, pyqtSignal
from PyQt6.QtGui import QAction
from PyQt6.QtWidgets import QCheckBox, QComboBox, QHBoxLayout, QLabel, QStyle, QToolButton, QWidget

from widgets.range_slider import RangeSlider

SPEEDS = (0.25, 0.5, 1.0, 2.0)
#: Playback paces (value, label, tooltip); the session's names.
PACES = (
    ("every_frame", "Every frame", "Solve every clip frame; playback waits for the solver"),
    ("real_time", "Real time", "Keep the clock; skip frames the solver has not reached"),
)


class Timeline(QWidget):
    """Playback controls; it only emits requests; the session decides.

    Signals
    -------
    playToggled(bool), stepRequested(int), seekRequested(int), speedChanged(float),
    loopChanged(bool), paceChanged(str), selectionChanged(int, int) (a frame range
    marked with Shift-click or Shift-drag; ``(-1, -1)`` when cleared)
    """

    playToggled = pyqtSignal(bool)
    stepRequested = pyqtSignal(int)
    seekRequested = pyqtSignal(int)
    speedChanged = pyqtSignal(float)
    loopChanged = pyqtSignal(bool)
    paceChanged = pyqtSignal(str)
    selectionChanged = pyqtSignal(int, int)

    def __init__(self, parent: QWidget | None = None) -> None:
        super().__init__(parent)
        row = QHBoxLayout(self)
        row.setContentsMargins(6, 2, 6, 2)
        icon = self.style().standardIcon
        self._icons = (icon(QStyle.StandardPixmap.SP_MediaPlay), icon(QStyle.StandardPixmap.SP_MediaPause))
        self.play_button = QToolButton(icon=self._icons[0], toolTip="Play / pause (Space)")
        self.play_button.setCheckable(True)
        self.play_button.toggled.connect(self._on_play)
        back = QToolButton(icon=icon(QStyle.StandardPixmap.SP_MediaSkipBackward), toolTip="Previous frame (Left)")
        back.clicked.connect(lambda: self.stepRequested.emit(-1))
        fwd = QToolButton(icon=icon(QStyle.StandardPixmap.SP_MediaSkipForward), toolTip="Next frame (Right)")
        fwd.clicked.connect(lambda: self.stepRequested.emit(1))
        self.slider = RangeSlider()
        self.slider.setToolTip("Scrub; Shift-click or Shift-drag selects a frame range, right click clears it")
        self.slider.selectionChanged.connect(self.selectionChanged.emit)
        self.slider.setMinimumWidth(160)  # a frame range must stay pickable beside the wide docks
        self.slider.setRange(0, 0)
        self.slider.valueChanged.connect(self._on_slider)
        self.counter = QLabel("0 / 0")
        self.counter.setFixedWidth(150)  # a changing width would relayout the row every frame
        self.counter.setAlignment(Qt.AlignmentFlag.AlignRight | Qt.AlignmentFlag.AlignVCenter)
        self.speed = QComboBox(toolTip="Playback speed")
        for s in SPEEDS:
            self.speed.addItem(f"{s:g}x", s)
        self.speed.setCurrentIndex(SPEEDS.index(1.0))
        self.speed.currentIndexChanged.connect(lambda i: self.speedChanged.emit(float(self.speed.itemData(i))))
        self.loop = QCheckBox("Loop", checked=True)
        self.loop.toggled.connect(self.loopChanged.emit)
        for w in (back, self.play_button, fwd):
            row.addWidget(w)
        row.addWidget(self.slider, 1)
        self.pace = QComboBox(toolTip="Playback pace: " + "; ".join(f"{lb}: {tip}" for _, lb, tip in PACES))
        for value, label, tip in PACES:
            self.pace.addItem(label, value)
            self.pace.setItemData(self.pace.count() - 1, tip, Qt.ItemDataRole.ToolTipRole)
        self.pace.currentIndexChanged.connect(self._on_pace)
        for w in (self.counter, self.speed, self.pace, self.loop):
            row.addWidget(w)
        self._row = row
        self._updating = False
        self._fps = 60.0

    def add_action(self, action: QAction) -> QToolButton:
        """A button at the end of the row for a window action (e.g. View ▸ Follow)."""
        button = QToolButton()
        button.setDefaultAction(action)
        self._row.addWidget(button)
        return button

    def _on_play(self, playing: bool) -> None:
        self.play_button.setIcon(self._icons[1] if playing else self._icons[0])
        if not self._updating:
            self.playToggled.emit(playing)

    def _on_pace(self, index: int) -> None:
        if not self._updating:
            self.paceChanged.emit(str(self.pace.itemData(index)))

    def set_pace(self, pace: str) -> None:
        """Show the session's playback pace without emitting."""
        self._updating = True
        self.pace.setCurrentIndex(max(self.pace.findData(pace), 0))
        self._updating = False

    def _on_slider(self, value: int) -> None:
        self._show_counter(value)
        if not self._updating:
            self.seekRequested.emit(value)

    def _show_counter(self, frame: int) -> None:
        text = f"{frame} / {self.slider.maximum()}  {frame / self._fps:5.2f}s"
        if text != self.counter.text():  # a label repaint is costly on software rendering
            self.counter.setText(text)

    def set_range(self, num_frames: int, fps: float = 60.0) -> None:
        self._fps = fps
        self._updating = True
        self.slider.setRange(0, max(num_frames - 1, 0))
        sel = self.slider.selection()
        if sel is not None and sel[0] > self.slider.maximum():  # a shorter clip cuts the range
            self.slider.set_selection(None)
        elif sel is not None:
            self.slider.set_selection(*sel)
        self._updating = False
        self._show_counter(self.slider.value())

    def selection(self) -> tuple[int, int] | None:
        """The selected frame range ``(start, end)``, inclusive, or None."""
        return self.slider.selection()

    def set_selection(self, start: int | None, end: int | None = None) -> None:
        """Select ``start..end`` (None clears); emits ``selectionChanged`` if it changed."""
        self.slider.set_selection(start, end)

    def set_constraint_span(self, span: tuple[int, int, int, int] | None) -> None:
        """Show the selected constraint's frame range ``(start, end, blend_in, blend_out)``
        on the scrub bar (None: it acts on every frame, or none is selected)."""
        self.slider.set_span(span)

    def set_marks(self, frames: list[int]) -> None:
        """Mark ``frames`` on the slider (red ticks: the frames latent debugging flags)."""
        self.slider.set_marks(frames)

    def set_frame(self, frame: int) -> None:
        """Show the engine's frame without emitting a seek (unless the user is dragging)."""
        if self.slider.isSliderDown():
            return
        self._updating = True
        self.slider.setValue(frame)
        self._updating = False
        # the slider's frame: a live stream's newest frame can run ahead of the range the
        # timeline was last given ("1557 / 1555")
        self._show_counter(self.slider.value())

    def set_playing(self, playing: bool) -> None:
        if playing == self.play_button.isChecked():
            return
        self._updating = True
        self.play_button.setChecked(playing)
        self._updating = False
