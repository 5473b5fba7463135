"""A constraint's frame range: its editor row and its span on a timeline.

Every constraint may act on frames ``start..end`` only, its weight rising over
``blend_in`` frames before and falling over ``blend_out`` frames after
(:meth:`engine.constraints.base.Constraint.activity`). :class:`FrameRangeEditor` edits
the three fields as one row of the constraint editor; :func:`paint_span` draws them on a
timeline (the studio's scrub bar, the pose window's key strip): a solid bar over the
range and a ramp over each blend, so a user sees where a pin holds and where it lets go.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

from PyQt6.QtCore import QPointF, pyqtSignal
from PyQt6.QtGui import QColor, QPainter, QPolygonF
from PyQt6.QtWidgets import QCheckBox, QGridLayout, QLabel, QSpinBox, QWidget

from widgets import style
from widgets.field_editing import commit_only, is_editing

#: The constraint fields the editor row owns (``engine.constraints.base.FRAME_FIELDS``).
FRAME_FIELDS = ("frames", "blend_in", "blend_out")
#: Largest frame offered (the scene format's longest animation, ten minutes at 60 fps).
MAX_FRAME = 36000 - 1
#: A constraint's range on a timeline: ``(start, end, blend_in, blend_out)`` frames.
Span = tuple[int, int, int, int]


def span_of(values: dict[str, Any]) -> Span | None:
    """The :data:`Span` of a constraint's ``to_dict()`` form, None when it acts on every frame."""
    frames = values.get("frames")
    if frames is None:
        return None
    return int(frames[0]), int(frames[1]), int(values.get("blend_in", 0)), int(values.get("blend_out", 0))


class FrameRangeEditor(QWidget):
    """*Every frame* or *frames start to end*, with the blends in and out (frames).

    ``changed(dict)`` carries one field: ``{"frames": (start, end)}`` or ``{"frames":
    None}``, ``{"blend_in": n}``, ``{"blend_out": n}``. Ticking *only frames* offers
    :attr:`default_range` (the window sets it: the timeline's selection, else the frames
    from the current one), so one tick restricts a pin made on a paused frame to the
    frames around it.
    """

    changed = pyqtSignal(dict)

    def __init__(self, values: dict[str, Any]) -> None:
        super().__init__()
        grid = QGridLayout(self)
        grid.setContentsMargins(0, 0, 0, 0)
        grid.setHorizontalSpacing(4)
        self.limited = QCheckBox("only frames")
        self.limited.setToolTip("Unticked: the constraint acts on every frame")
        self.start = commit_only(QSpinBox(minimum=0, maximum=MAX_FRAME))
        self.end = commit_only(QSpinBox(minimum=0, maximum=MAX_FRAME))
        self.blend_in = commit_only(QSpinBox(minimum=0, maximum=MAX_FRAME, suffix=" in"))
        self.blend_out = commit_only(QSpinBox(minimum=0, maximum=MAX_FRAME, suffix=" out"))
        self.start.setToolTip("First frame it acts on fully")
        self.end.setToolTip("Last frame it acts on fully")
        self.blend_in.setToolTip("Frames before the start over which it fades in")
        self.blend_out.setToolTip("Frames after the end over which it fades out")
        grid.addWidget(self.limited, 0, 0)
        grid.addWidget(self.start, 0, 1)
        grid.addWidget(QLabel("to"), 0, 2)
        grid.addWidget(self.end, 0, 3)
        grid.addWidget(QLabel("blend"), 1, 0)
        grid.addWidget(self.blend_in, 1, 1)
        grid.addWidget(self.blend_out, 1, 3)
        #: ``() -> (start, end)`` offered when *only frames* is ticked.
        self.default_range: Callable[[], tuple[int, int]] = lambda: (0, 60)
        self.set_values(values)
        self.limited.toggled.connect(self._limit)
        self.start.valueChanged.connect(lambda v: self._range(int(v), max(int(v), self.end.value())))
        self.end.valueChanged.connect(lambda v: self._range(min(self.start.value(), int(v)), int(v)))
        self.blend_in.valueChanged.connect(lambda v: self.changed.emit({"blend_in": int(v)}))
        self.blend_out.valueChanged.connect(lambda v: self.changed.emit({"blend_out": int(v)}))

    def set_frame_count(self, frames: int) -> None:
        """Bound start and end by the clip or animation's ``frames`` (a range may still
        reach past them: the clip can grow)."""
        top = max(0, int(frames) - 1)
        for spin in (self.start, self.end):
            spin.setMaximum(max(top, spin.value()))

    def spins(self) -> tuple[QSpinBox, ...]:
        return self.start, self.end, self.blend_in, self.blend_out

    def set_values(self, values: dict[str, Any]) -> None:
        """Show a constraint's ``frames``, ``blend_in``, ``blend_out`` without emitting; a
        number the user is typing keeps what is typed."""
        widgets = (self.limited, *self.spins())
        for w in widgets:
            w.blockSignals(True)
        try:
            frames = values.get("frames")
            self.limited.setChecked(frames is not None)
            shown = [(self.blend_in, values.get("blend_in", 0)), (self.blend_out, values.get("blend_out", 0))]
            if frames is not None:
                shown += [(self.start, frames[0]), (self.end, frames[1])]
            for spin, v in shown:
                if not is_editing(spin):
                    spin.setMaximum(max(spin.maximum(), int(v)))
                    spin.setValue(int(v))
        finally:
            for w in widgets:
                w.blockSignals(False)
        for w in self.spins():
            w.setEnabled(frames is not None)

    def _limit(self, on: bool) -> None:
        for w in self.spins():
            w.setEnabled(on)
        if not on:
            self.changed.emit({"frames": None})
            return
        start, end = self.default_range()
        self._range(int(start), int(end))

    def _range(self, start: int, end: int) -> None:
        for spin, v in ((self.start, start), (self.end, end)):
            spin.blockSignals(True)
            spin.setMaximum(max(spin.maximum(), v))
            spin.setValue(v)
            spin.blockSignals(False)
        self.changed.emit({"frames": (start, end)})


def paint_span(p: QPainter, x_of: Callable[[int], float], span: Span, top: float, height: float) -> None:
    """Draw ``span`` in the gizmos' colour: a bar from ``start`` to ``end`` (each frame's
    width, at least 3 pixels) and a ramp over each blend, within ``top..top + height``."""
    start, end, blend_in, blend_out = span
    colour = QColor(style.GIZMO)
    x0, x1 = x_of(start), x_of(end)
    bottom = top + height
    p.setPen(colour)
    fill = QColor(colour)
    fill.setAlpha(110)
    p.setBrush(fill)
    left, right = x_of(max(0, start - blend_in)), x_of(end + blend_out)
    p.drawPolygon(QPolygonF([QPointF(left, bottom), QPointF(x0, top), QPointF(x1, top), QPointF(right, bottom)]))
    p.setBrush(colour)
    p.drawRect(int(x0) - 1, int(top), max(int(x1 - x0), 0) + 2, int(height))
