"""Ghost drawables: other methods' poses as thin translucent skeletons, one colour each.

Ghosts are drawn in an overlay renderer (VTK layer 1) that shares the main camera, so a
ghost that runs through or behind the reconstruction still shows through it instead of
hiding under the thicker opaque figure. They are lines and point sprites only, so the
extra pass costs little even on software GL.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
import pyvista as pv
import vtk

from engine import skeleton as sk
from widgets import style

GHOST_OPACITY = 0.55
GHOST_BONE_WIDTH = 3.0  # pixels; the reconstruction's are 7
GHOST_JOINT_SIZE = 5.0
LEGEND_ROW = 20  # pixels between legend lines


class GhostSkeleton:
    """One method's pose as a translucent stick figure in ``renderer`` (moved in place)."""

    def __init__(self, renderer: vtk.vtkRenderer, color: str, opacity: float = GHOST_OPACITY) -> None:
        lines = np.array([[2, p, j] for j, p in enumerate(sk.PARENTS) if p >= 0]).ravel()
        self.mesh = pv.PolyData(sk.Skeleton.canonical().rest_positions().astype(float), lines=lines)
        self.color = color
        self.actors = []
        for points in (False, True):
            mapper = vtk.vtkPolyDataMapper()
            mapper.SetInputData(self.mesh)
            actor = vtk.vtkActor()
            actor.SetMapper(mapper)
            actor.PickableOff()
            prop = actor.GetProperty()
            prop.SetColor(*style.hex_to_unit_rgb(color))
            prop.SetOpacity(opacity)
            if points:
                prop.SetRepresentationToPoints()
                prop.SetPointSize(GHOST_JOINT_SIZE)
                prop.RenderPointsAsSpheresOn()
            else:
                prop.SetRepresentationToWireframe()
                prop.SetLineWidth(GHOST_BONE_WIDTH)
            renderer.AddActor(actor)
            self.actors.append(actor)
        self._renderer = renderer
        self.visible = True

    def update(self, positions: np.ndarray | None) -> None:
        """Move to ``positions`` (22, 3) metres; None (or non-finite) hides the ghost."""
        if positions is None or not np.all(np.isfinite(positions)):
            self.set_visible(False)
            return
        self.mesh.points[:] = positions
        self.mesh.GetPoints().Modified()
        self.set_visible(True)

    def set_visible(self, visible: bool) -> None:
        if visible != self.visible:
            self.visible = visible
            for a in self.actors:
                a.SetVisibility(visible)

    def remove(self) -> None:
        for a in self.actors:
            self._renderer.RemoveActor(a)


class GhostLayer:
    """Every ghost method's skeleton, created on first sight, in an overlay renderer.

    Parameters
    ----------
    plotter : pyvista.Plotter
        The viewport's plotter; the overlay shares its camera.
    color_of : callable
        ``color_of(method name, index) -> hex colour``; methods keep their colour.
    """

    def __init__(self, plotter: pv.Plotter, color_of: Callable[[str, int], str] = style.ghost_color) -> None:
        self.color_of = color_of
        self.renderer = vtk.vtkRenderer()
        window = plotter.render_window
        window.SetNumberOfLayers(max(window.GetNumberOfLayers(), 2))
        self.renderer.SetLayer(1)
        self.renderer.SetActiveCamera(plotter.renderer.GetActiveCamera())
        self.renderer.InteractiveOff()
        self.renderer.SetBackgroundAlpha(0.0)
        window.AddRenderer(self.renderer)
        self.items: dict[str, GhostSkeleton] = {}
        self.labels: dict[str, vtk.vtkTextActor] = {}
        self.visible = True

    def update(self, ghosts: dict[str, np.ndarray]) -> None:
        """Draw ``{method: positions (22, 3)}``; methods missing from it are hidden.
        The legend (top left) names each ghost shown, in its colour."""
        for i, (name, pos) in enumerate(ghosts.items()):
            if name not in self.items:
                self.items[name] = GhostSkeleton(self.renderer, self.color_of(name, i))
                self.labels[name] = self._label(name, self.items[name].color)
            self.items[name].update(pos if self.visible else None)
        row, height = 0, self.renderer.GetSize()[1]
        for name, item in self.items.items():
            if name not in ghosts:
                item.set_visible(False)
            label = self.labels[name]
            shown = name in ghosts and self.visible
            label.SetVisibility(shown)
            if shown:
                label.SetDisplayPosition(12, max(0, height - 46 - LEGEND_ROW * row))  # under the caption line
                row += 1

    def _label(self, name: str, color: str) -> vtk.vtkTextActor:
        actor = vtk.vtkTextActor()
        actor.SetInput(f"- {name}")
        prop = actor.GetTextProperty()
        prop.SetColor(*style.hex_to_unit_rgb(color))
        prop.SetFontSize(15)
        prop.BoldOn()
        actor.PickableOff()
        self.renderer.AddViewProp(actor)
        return actor

    def close(self) -> None:
        for item in self.items.values():
            item.remove()
        for label in self.labels.values():
            self.renderer.RemoveViewProp(label)
        self.items, self.labels = {}, {}
