"""Motion paths in the 3D view: a few joints' trajectories as lines, dots on the keys and
a larger dot on the current frame (Blender's and Cascadeur's motion paths).

Three polydata, made once and updated in place: every path's polyline in one (each
point coloured by its path), the marked frames' dots in another, the current frame's
dots in a third. A new set of paths rewrites the first two; a new frame moves only the
few points of the third, so playing costs one small array copy per drawn frame.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence

import numpy as np
import pyvista as pv
import vtk

from widgets import style

#: Line width of a path, pixels (plain lines: tubes cost much more on software GL).
PATH_WIDTH = 3.0
#: Pixel sizes of a marked frame's (key's) dot and of the current frame's.
MARK_SIZE = 8.0
CURRENT_SIZE = 14.0
MARK_COLOUR = "#f2f4f8"
CURRENT_COLOUR = "#ff4dd2"


def polylines(lines: Sequence[np.ndarray]) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Points ``(N, 3)``, VTK line cells and each point's line index ``(N,)`` of
    ``lines`` (each ``(n, 3)`` metres); a non-finite point breaks its line there."""
    points, cells, owner = [], [], []
    at = 0
    for k, line in enumerate(lines):
        line = np.asarray(line, float).reshape(-1, 3)
        finite = np.all(np.isfinite(line), axis=1)
        # runs of finite points, each a polyline of two points or more
        edges = np.flatnonzero(np.diff(np.r_[0, finite.astype(np.int8), 0]))
        for start, end in zip(edges[::2], edges[1::2]):
            if end - start < 2:
                continue
            points.append(line[start:end])
            owner.append(np.full(end - start, k))
            cells.append(np.r_[end - start, np.arange(at, at + end - start)])
            at += end - start
    if not points:
        return np.zeros((0, 3)), np.zeros(0, np.int64), np.zeros(0, np.int64)
    return np.concatenate(points), np.concatenate(cells).astype(np.int64), np.concatenate(owner)


class MotionPathLayer:
    """The paths of one plotter (hidden until :meth:`show`); see the module doc."""

    def __init__(self, plotter: pv.Plotter) -> None:
        self._plotter = plotter
        self.lines = pv.PolyData()
        self.marks = pv.PolyData()
        self.current = pv.PolyData()
        #: The paths shown: name -> (n, 3) metres for frames ``first ..``, and their colours.
        self.paths: dict[str, np.ndarray] = {}
        self.first = 0
        #: The frame the current-frame dots are on (None: they were put by :meth:`mark_current`).
        self.frame: int | None = None
        self.actors: list[vtk.vtkActor] = []
        for mesh, kind in ((self.lines, "lines"), (self.marks, "marks"), (self.current, "current")):
            mapper = vtk.vtkPolyDataMapper()
            mapper.SetInputData(mesh)
            actor = vtk.vtkActor()
            actor.SetMapper(mapper)
            actor.PickableOff()
            prop = actor.GetProperty()
            prop.LightingOff()
            if kind == "lines":
                mapper.SetColorModeToDirectScalars()
                mapper.SetScalarModeToUsePointData()
                prop.SetLineWidth(PATH_WIDTH)
            else:
                mapper.ScalarVisibilityOff()
                prop.SetRepresentationToPoints()
                prop.RenderPointsAsSpheresOn()
                prop.SetPointSize(MARK_SIZE if kind == "marks" else CURRENT_SIZE)
                prop.SetColor(*style.hex_to_unit_rgb(MARK_COLOUR if kind == "marks" else CURRENT_COLOUR))
            actor.SetVisibility(False)
            plotter.renderer.AddActor(actor)
            self.actors.append(actor)

    @property
    def shown(self) -> bool:
        """Whether any path is drawn."""
        return bool(self.actors) and bool(self.actors[0].GetVisibility())

    def show(
        self,
        first: int,
        paths: Mapping[str, np.ndarray],
        colours: Mapping[str, str],
        marks: Sequence[int] = (),
    ) -> None:
        """Draw ``paths`` (name -> ``(n, 3)`` metres, row ``i`` on frame ``first + i``)
        each in its colour, with a dot on each frame of ``marks`` along every path.
        Empty ``paths`` hide everything; after :meth:`clear` nothing is drawn."""
        if not self.actors:
            return
        self.paths = {name: np.asarray(p, float).reshape(-1, 3) for name, p in paths.items()}
        self.first = int(first)
        points, cells, owner = polylines(list(self.paths.values()))
        if len(points) == 0:
            self.hide()
            return
        palette = np.array([style.hex_to_rgb(colours[name]) for name in self.paths], np.uint8)
        self.lines.points = points
        self.lines.lines = cells
        self.lines.point_data.set_scalars(palette[owner], "rgb")
        rows = [f - self.first for f in marks]
        dots = [p[r] for p in self.paths.values() for r in rows if 0 <= r < len(p) and np.all(np.isfinite(p[r]))]
        self._set_points(self.marks, np.array(dots).reshape(-1, 3))
        for actor, on in zip(self.actors[:2], (True, bool(dots))):
            actor.SetVisibility(on)
        if self.frame is not None:
            self.at_frame(self.frame)
        else:
            self.actors[2].SetVisibility(self.current.n_points > 0)

    def at_frame(self, frame: int) -> None:
        """The current-frame dots on ``frame`` of every path (none outside their frames)."""
        self.frame = int(frame)
        r = self.frame - self.first
        dots = [p[r] for p in self.paths.values() if 0 <= r < len(p) and np.all(np.isfinite(p[r]))]
        self._mark(np.array(dots).reshape(-1, 3))

    def mark_current(self, points: np.ndarray) -> None:
        """The current-frame dots at ``points (M, 3)`` metres (the pose being dragged)."""
        self.frame = None
        self._mark(np.asarray(points, float).reshape(-1, 3))

    def _mark(self, points: np.ndarray) -> None:
        if not self.actors:
            return
        self._set_points(self.current, points)
        self.actors[2].SetVisibility(self.shown and len(points) > 0)

    def hide(self) -> None:
        self.paths = {}
        for actor in self.actors:
            actor.SetVisibility(False)

    @staticmethod
    def _set_points(mesh: pv.PolyData, points: np.ndarray) -> None:
        if mesh.n_points == len(points) and len(points):
            mesh.points[:] = points  # the same few points moved: no new arrays
            mesh.GetPoints().Modified()
            return
        mesh.points = points if len(points) else np.zeros((0, 3))
        mesh.verts = np.c_[np.ones(len(points), np.int64), np.arange(len(points))].ravel()

    def clear(self) -> None:
        for actor in self.actors:
            self._plotter.renderer.RemoveActor(actor)
        self.actors = []
