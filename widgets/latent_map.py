"""The latent map: the clip's latents on a fixed 2D view of the latent space.

Drawn on the shipped projection (engine/latent/projection.py, handed in with
:meth:`LatentMapPlot.set_map`): the training latents as a grey density, every frame solved
since the clip was opened (a :class:`engine.latent.solved_frames.SolvedFrames`, so a seek
that restarts the engine's history keeps the trajectory) coloured by frame (dark blue
first, yellow last), flagged frames as red crosses, the frame on screen as a white ring, and its solve's iterations as an orange path
from its start, labelled by where the solve started; after an inspection, each term's
force in the map plane as a line in its loss-plot colour (:meth:`LatentMapPlot.set_forces`),
and the Latent panel's stored A and B with the A to B blend's path (dashed).

The mouse asks, the window answers: hovering emits ``pointHovered(x, y)`` (or
``frameHovered(frame)`` near a trajectory point), a left click ``pointClicked(x, y)`` (or
``frameClicked(frame)``). The window decodes the point as a ghost pose or seeks the frame.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import pyqtgraph as pg
from PyQt6.QtCore import QPointF, QRectF, Qt, pyqtSignal
from PyQt6.QtGui import QCloseEvent
from PyQt6.QtWidgets import QCheckBox, QLabel, QVBoxLayout, QWidget

from engine.latent.solved_frames import SolvedFrames
from widgets.latent_readouts import consecutive
from widgets.plots import release

#: A trajectory point within this many pixels of the mouse is the one pointed at.
PICK_PX = 8.0
#: *Zoom to the clip* shows the trajectory with this margin (map units) around it.
ZOOM_MARGIN = 0.8
#: Colours of the time scale (oldest to newest frame).
TIME_STEPS = 24
PATH_COLOUR = "#ff8a1f"
FLAG_COLOUR = "#ff3b30"
HOVER_COLOUR = "#00e5ff"


class LatentMapPlot(QWidget):
    """See the module doc. Feed it snapshots with :meth:`update_snapshot`; ``solved``
    is the store of solved frames it reads and feeds (the window shares one with the
    readouts)."""

    pointHovered = pyqtSignal(float, float)
    frameHovered = pyqtSignal(int)
    pointClicked = pyqtSignal(float, float)
    frameClicked = pyqtSignal(int)

    def __init__(self, parent: QWidget | None = None, solved: SolvedFrames | None = None) -> None:
        super().__init__(parent)
        self.solved = solved if solved is not None else SolvedFrames()
        layout = QVBoxLayout(self)
        layout.setContentsMargins(0, 0, 0, 0)
        self.note = QLabel("")
        self.note.setWordWrap(True)
        self.note.setStyleSheet("color: #8a93a6;")
        self.note.setVisible(False)
        self.plot = pg.PlotWidget()
        # 100 px high at least, not 200: the readouts under the map share the dock with it
        self.plot.setMinimumSize(200, 100)
        self.setToolTip(
            "Latent map: hover or click to decode a point as a ghost pose; click a trajectory point to go to its frame"
        )
        for side in ("bottom", "left"):
            self.plot.getAxis(side).enableAutoSIPrefix(False)
        self.plot.setMenuEnabled(False)
        self.plot.setAspectLocked(True)  # directions on the map (forces, paths) as they are
        self.zoom = QCheckBox("Zoom to the clip", checked=True)
        self.zoom.setToolTip("Keep the clip's trajectory in view; zooming or panning with the mouse turns it off")
        self.zoom.toggled.connect(lambda on: self._fit() if on else None)
        self.plot.getPlotItem().getViewBox().sigRangeChangedManually.connect(lambda *_: self.zoom.setChecked(False))
        self.density = pg.ImageItem()
        self.density.setColorMap(pg.colormap.get("CET-L1"))  # black to white: the training data as light
        self.plot.addItem(self.density)
        self.line = self.plot.plot(pen=pg.mkPen((200, 200, 200, 90), width=1))
        self.points = pg.ScatterPlotItem(size=5, pen=None)
        self.flags = pg.ScatterPlotItem(size=9, symbol="x", pen=None, brush=FLAG_COLOUR)
        self.path = self.plot.plot(
            pen=pg.mkPen(PATH_COLOUR, width=1.5), symbol="o", symbolSize=4, symbolBrush=PATH_COLOUR, symbolPen=None
        )
        self.start_label = pg.TextItem("", color=PATH_COLOUR, anchor=(0, 1))
        self.current = pg.ScatterPlotItem(size=13, pen=pg.mkPen("w", width=2), brush=None)
        self.hover = pg.ScatterPlotItem(size=11, symbol="+", pen=pg.mkPen(HOVER_COLOUR, width=2))
        self.blend = self.plot.plot(pen=pg.mkPen("#ffffff", width=1, style=Qt.PenStyle.DashLine))
        # named by set_blend: an "A" and a "B" made with their text sat on the map's origin
        # until the Latent panel stored anything
        self.blend_labels = (pg.TextItem("", color="#ffffff"), pg.TextItem("", color="#ffffff"))
        for item in (self.points, self.flags, self.current, self.hover, self.start_label, *self.blend_labels):
            self.plot.addItem(item)
        layout.addWidget(self.note)
        layout.addWidget(self.zoom)
        layout.addWidget(self.plot, 1)
        # time colours in a few steps, the same brush objects every update: pyqtgraph renders
        # a symbol per distinct brush, and 600 distinct ones cost ~0.4 s per update
        self._brushes = [
            pg.mkBrush(c) for c in pg.colormap.get("viridis").map(np.linspace(0, 1, TIME_STEPS), mode="qcolor")
        ]
        self.frames = np.zeros(0, int)
        self.xy = np.zeros((0, 2))
        self._drawn = (-1, -1)  # (snapshot seq, store version) drawn
        self._explained: tuple[float, float] | None = None
        self._extent = (-1.0, 1.0, -1.0, 1.0)
        self._path = np.zeros((0, 2))
        self.force_lines: list = []
        scene = self.plot.scene()
        scene.sigMouseMoved.connect(self._moved)
        scene.sigMouseClicked.connect(self._clicked)

    # -- data ---------------------------------------------------------------------------
    def closeEvent(self, event: QCloseEvent | None) -> None:  # noqa: N802 (Qt's name)
        """A closed view holds no plot item (:func:`widgets.plots.release`)."""
        self.force_lines = []
        release(self.plot)
        super().closeEvent(event)

    def set_map(self, density: np.ndarray, extent: np.ndarray, explained: np.ndarray) -> None:
        """The training density ``(G, G)`` (rows y, columns x) over ``extent`` (x0, x1, y0,
        y1) and the axes' explained variance fractions ``(2,)``."""
        d = np.log1p(np.asarray(density, float))
        self.density.setImage(np.ascontiguousarray(d.T), levels=(0.0, max(float(d.max()), 1e-9)))
        x0, x1, y0, y1 = (float(v) for v in extent)
        self.density.setRect(QRectF(x0, y0, x1 - x0, y1 - y0))
        self.plot.setXRange(x0, x1, padding=0.0)
        self.plot.setYRange(y0, y1, padding=0.0)
        self._extent = (x0, x1, y0, y1)
        self._explained = (float(explained[0]), float(explained[1]))
        self.plot.setLabel("bottom", f"PC 1 ({100 * explained[0]:.1f} % of variance)")
        self.plot.setLabel("left", f"PC 2 ({100 * explained[1]:.1f} % of variance)")

    def set_note(self, text: str) -> None:
        """Say why the map is empty (e.g. the method has no latent); "" hides the note."""
        if text != self.note.text():
            self.note.setText(text)
        self.note.setVisible(bool(text))

    def update_snapshot(self, snap: Any) -> None:
        """Draw every solved frame (``snap.history`` read into :attr:`solved` first) and
        the frame on screen."""
        self.solved.note(snap.history)
        if (snap.seq, self.solved.version) == self._drawn:
            return
        self._drawn = (snap.seq, self.solved.version)
        view = snap.latent_view
        self.set_note(snap.latent_note if view is None else "")
        s = self.solved
        placed = np.isfinite(s.xy).all(axis=1)  # a record without map coordinates is not drawn
        self.frames, self.xy = s.frames[placed], s.xy[placed]
        if len(self.frames):
            t = (self.frames - self.frames.min()) / max(int(np.ptp(self.frames)), 1)
            steps = np.rint(t * (TIME_STEPS - 1)).astype(int)
            self.points.setData(self.xy[:, 0], self.xy[:, 1], brush=[self._brushes[i] for i in steps])
            self.line.setData(self.xy[:, 0], self.xy[:, 1], connect=consecutive(self.frames))
        else:
            self.points.setData([], [])
            self.line.setData([], [])
        flagged = s.flagged[placed]
        self.flags.setData(self.xy[flagged, 0], self.xy[flagged, 1])
        if view is None:
            self._show_frame(None)
            return
        self._show_frame(view)

    def mark_stale(self) -> None:
        """Draw the next snapshot even if it is the one drawn last (a view brought back
        into sight after it skipped snapshots)."""
        self._drawn = (-1, -1)

    def clear(self) -> None:
        """Nothing solved yet (another clip or method): no trajectory, no frame on screen."""
        self.solved.clear()
        self.mark_stale()
        self.frames, self.xy = np.zeros(0, int), np.zeros((0, 2))
        for item in (self.points, self.line, self.flags):
            item.setData([], [])
        self._show_frame(None)
        self.set_forces(None)

    def _show_frame(self, view: Any) -> None:
        """The frame on screen's ring and its solve's path (None hides them)."""
        if view is None:
            self.current.setData([], [])
            self.path.setData([], [])
            self.start_label.setText("")
            self._path = np.zeros((0, 2))
            return
        self.current.setData([view.xy[0]], [view.xy[1]])
        self._path = np.asarray(view.path_xy if view.path_xy is not None else view.xy[None], float).reshape(-1, 2)
        self._fit()
        if view.path_xy is not None and len(view.path_xy):
            self.path.setData(view.path_xy[:, 0], view.path_xy[:, 1])
            self.start_label.setText(f"start: {view.start}" if view.start else "start")
            self.start_label.setPos(float(view.path_xy[0, 0]), float(view.path_xy[0, 1]))
        else:
            self.path.setData([], [])
            self.start_label.setText("")

    def _fit(self) -> None:
        """With *Zoom to the clip*: the trajectory and the frame's path in view, with
        :data:`ZOOM_MARGIN` around them (the whole map when there is nothing yet)."""
        if not self.zoom.isChecked():
            return
        pts = np.vstack([self.xy, self._path]) if len(self.xy) or len(self._path) else np.zeros((0, 2))
        if not len(pts):
            x0, x1, y0, y1 = self._extent
        else:
            (x0, y0), (x1, y1) = pts.min(0) - ZOOM_MARGIN, pts.max(0) + ZOOM_MARGIN
        # setRange emits the range signals the axes and grid follow, never
        # sigRangeChangedManually (mouse only), so the box stays ticked
        self.plot.setRange(xRange=(x0, x1), yRange=(y0, y1), padding=0.0)

    def set_blend(self, a: np.ndarray | None, b: np.ndarray | None) -> None:
        """The Latent panel's stored latents A and B at map points ``a``, ``b`` (2,), and the
        A to B blend's path between them (a straight line: the projection is linear);
        None hides them."""
        if a is None or b is None:
            self.blend.setData([], [])
            for t in self.blend_labels:
                t.setText("")
            return
        self.blend.setData([a[0], b[0]], [a[1], b[1]])
        for t, p, name in zip(self.blend_labels, (a, b), "AB"):
            t.setText(name)
            t.setPos(float(p[0]), float(p[1]))

    def set_forces(
        self, origin: np.ndarray | None, vectors: np.ndarray | None = None, colours: list[str] | None = None
    ) -> None:
        """Draw each term's force in the map plane as a line from ``origin (2,)`` along
        ``vectors (T, 2)`` in ``colours`` (the loss plots' term colours), the longest a
        quarter of the view's width; None clears them."""
        for item in self.force_lines:
            self.plot.removeItem(item)
        self.force_lines = []
        if origin is None or vectors is None or not len(vectors):
            return
        v = np.asarray(vectors, float)
        longest = float(np.linalg.norm(v, axis=1).max())
        if longest <= 0:
            return
        (x0, x1), _ = self.plot.getPlotItem().getViewBox().viewRange()
        v = v * (0.25 * (x1 - x0) / longest)
        for vec, colour in zip(v, colours or ["#ffffff"] * len(v)):
            item = self.plot.plot(
                [origin[0], origin[0] + vec[0]], [origin[1], origin[1] + vec[1]], pen=pg.mkPen(colour, width=2)
            )
            self.force_lines.append(item)

    # -- mouse ----------------------------------------------------------------------------
    def to_view(self, scene_pos: QPointF) -> tuple[float, float] | None:
        """Map coordinates of a scene position, None outside the plot's view box."""
        vb = self.plot.getPlotItem().getViewBox()
        if not vb.sceneBoundingRect().contains(scene_pos):
            return None
        p = vb.mapSceneToView(scene_pos)
        return float(p.x()), float(p.y())

    def to_widget(self, x: float, y: float) -> QPointF:
        """The plot viewport's pixel position of map point ``(x, y)`` (tests aim with it)."""
        vb = self.plot.getPlotItem().getViewBox()
        return QPointF(self.plot.mapFromScene(vb.mapViewToScene(QPointF(x, y))))

    def frame_near(self, scene_pos: QPointF) -> int | None:
        """The solved frame whose trajectory point lies within :data:`PICK_PX` pixels."""
        xy = self.to_view(scene_pos)
        if xy is None or not len(self.xy):
            return None
        px, py = self.plot.getPlotItem().getViewBox().viewPixelSize()  # map units per pixel
        d = np.hypot((self.xy[:, 0] - xy[0]) / px, (self.xy[:, 1] - xy[1]) / py)
        i = int(np.argmin(d))
        return int(self.frames[i]) if d[i] <= PICK_PX else None

    def _moved(self, scene_pos: QPointF) -> None:
        xy = self.to_view(scene_pos)
        if xy is None:
            self.hover.setData([], [])
            return
        self.hover.setData([xy[0]], [xy[1]])
        frame = self.frame_near(scene_pos)
        if frame is not None:
            self.frameHovered.emit(frame)
        else:
            self.pointHovered.emit(*xy)

    def _clicked(self, event: Any) -> None:
        if event.button() != Qt.MouseButton.LeftButton:
            return
        xy = self.to_view(event.scenePos())
        if xy is None:
            return
        frame = self.frame_near(event.scenePos())
        if frame is not None:
            self.frameClicked.emit(frame)
        else:
            self.pointClicked.emit(*xy)
