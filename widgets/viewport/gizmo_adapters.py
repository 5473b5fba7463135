"""One viewport adapter per gizmo shape (:mod:`engine.gizmos`), registered by shape class.

An adapter owns the PyVista actors (and the VTK handle widget, when the shape names an
``edit`` field) of one constraint's gizmo. :meth:`GizmoAdapter.fits` says whether a
newer shape can be taken in place; :meth:`GizmoAdapter.update` then moves the geometry
without rebuilding it. A drag calls ``on_edit(constraint name, {field: value})``.

:data:`GIZMO_ADAPTERS` maps each shape class to its adapter; adding a shape means adding
its adapter class here and one entry in the table.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any, ClassVar

import numpy as np
import pyvista as pv
import vtk

from engine.gizmos import BoxGizmo, Gizmo, LineGizmo, PointGizmo
from widgets import style

EditCallback = Callable[[str, dict[str, Any]], None]

_LABEL_LIFT = np.array([0.0, 0.0, 0.07])  # metres above the point, so the text clears the handle
_HANDLE_RADIUS = 0.04  # metres
#: VTK observer priorities of the gizmos' widgets (3D widgets default to 0.5; a higher
#: one sees a press first). A point handle inside an editable box is covered by the
#: box's faces on screen: the small handle must be asked first, and the box takes the
#: press only when no handle was hit.
HANDLE_PRIORITY = 0.6
BOX_PRIORITY = 0.5


def set_priority(widget: Any, priority: float) -> None:
    """Give an enabled VTK 3D ``widget`` the observer ``priority``: its interactor
    observers are registered when it is switched on, so it is switched off and on again."""
    widget.Off()
    widget.SetPriority(priority)
    widget.On()


class GizmoAdapter:
    """Base of the adapters: the actors and the optional drag handle of one gizmo.

    Attributes
    ----------
    name : str
        The constraint the gizmo belongs to.
    gizmo : Gizmo
        The shape last drawn.
    widget : vtk widget or None
        The drag handle, when the shape is editable.
    dragging : bool
        True between the handle's start and end of interaction; snapshots arriving
        meanwhile do not move the handle back under the user's pointer.
    """

    shape: ClassVar[type[Gizmo]] = Gizmo

    def __init__(self, plotter: pv.Plotter, name: str, gizmo: Gizmo, on_edit: EditCallback) -> None:
        self.plotter, self.name, self.on_edit = plotter, name, on_edit
        self.gizmo = gizmo
        self.actors: list[Any] = []
        self.widget: Any = None
        self.dragging = False

    def fits(self, gizmo: Gizmo) -> bool:
        """Whether ``gizmo`` can be drawn by moving this adapter's geometry in place."""
        return type(gizmo) is type(self.gizmo) and gizmo.edit_fields == self.gizmo.edit_fields

    def update(self, gizmo: Gizmo) -> None:
        """Move the geometry to ``gizmo`` (which :meth:`fits`)."""
        raise NotImplementedError

    def remove(self) -> None:
        if self.widget is not None:
            self.widget.Off()
        if self.actors:
            self.plotter.remove_actor(self.actors, render=False)

    # -- shared parts ----------------------------------------------------------------
    def _add_mesh(self, mesh: pv.PolyData, **kw: Any) -> None:
        self.actors.append(self.plotter.add_mesh(mesh, color=style.GIZMO, reset_camera=False, **kw))

    def _add_handle(self, center: np.ndarray, field: str) -> None:
        """A draggable sphere at ``center`` that writes ``field`` back while dragged."""

        def moved(c: np.ndarray) -> None:
            if self.dragging:
                self.on_edit(self.name, {field: np.asarray(c, float)})

        self.widget = self.plotter.add_sphere_widget(
            moved,
            center=tuple(center),
            radius=_HANDLE_RADIUS,
            color=style.GIZMO,
            interaction_event="always",
            test_callback=False,
            style="wireframe",
        )
        set_priority(self.widget, HANDLE_PRIORITY)
        self.widget.AddObserver("StartInteractionEvent", lambda *_: setattr(self, "dragging", True))
        self.widget.AddObserver("EndInteractionEvent", lambda *_: setattr(self, "dragging", False))

    def _handle_at(self, center: np.ndarray) -> np.ndarray:
        """Put the handle at ``center`` unless the user holds it; returns where it is."""
        if self.dragging:
            return np.asarray(self.widget.GetCenter(), float)
        self.widget.SetCenter(*center)
        return center

    @staticmethod
    def _move(mesh: pv.PolyData, points: np.ndarray) -> None:
        mesh.points[:] = points
        mesh.GetPoints().Modified()


class PointAdapter(GizmoAdapter):
    """A :class:`~engine.gizmos.PointGizmo`: a dot, or a sphere handle when editable,
    with its label and the tether from its anchor when it has them."""

    shape = PointGizmo

    def __init__(self, plotter: pv.Plotter, name: str, gizmo: PointGizmo, on_edit: EditCallback) -> None:
        super().__init__(plotter, name, gizmo, on_edit)
        p = gizmo.position
        self.mesh: pv.PolyData | None = None
        self.tether: pv.PolyData | None = None
        self.label: Any = None
        if gizmo.edit:
            self._add_handle(p, gizmo.edit)
        else:
            self.mesh = pv.PolyData(p[None].copy())
            self._add_mesh(self.mesh, point_size=14, render_points_as_spheres=True)
        if gizmo.anchor is not None:
            self.tether = pv.lines_from_points(np.stack([gizmo.anchor, p]))
            self._add_mesh(self.tether, line_width=1, pickable=False)
        if gizmo.label:
            self._add_label(gizmo.label, p)

    def _add_label(self, text: str, p: np.ndarray) -> None:
        self.label = vtk.vtkBillboardTextActor3D()
        self.label.SetInput(text)
        self.label.SetPosition(*(p + _LABEL_LIFT))
        prop = self.label.GetTextProperty()
        prop.SetFontSize(14)
        prop.SetColor(*style.hex_to_unit_rgb(style.GIZMO))
        prop.SetJustificationToCentered()
        self.label.PickableOff()
        self.plotter.add_actor(self.label, reset_camera=False, render=False)
        self.actors.append(self.label)

    def fits(self, gizmo: Gizmo) -> bool:
        old = self.gizmo
        return (
            super().fits(gizmo)
            and isinstance(gizmo, PointGizmo)
            and isinstance(old, PointGizmo)
            and gizmo.label == old.label
            and (gizmo.anchor is None) == (old.anchor is None)
        )

    def update(self, gizmo: PointGizmo) -> None:
        self.gizmo = gizmo
        p = gizmo.position
        if self.widget is not None:
            p = self._handle_at(p)
        else:
            self._move(self.mesh, p[None])
        if self.tether is not None and gizmo.anchor is not None:
            self._move(self.tether, np.stack([gizmo.anchor, p]))
        if self.label is not None:
            self.label.SetPosition(*(p + _LABEL_LIFT))


class LineAdapter(GizmoAdapter):
    """A :class:`~engine.gizmos.LineGizmo`: a polyline whose last point is a handle
    when editable (the point a look-at aims at)."""

    shape = LineGizmo

    def __init__(self, plotter: pv.Plotter, name: str, gizmo: LineGizmo, on_edit: EditCallback) -> None:
        super().__init__(plotter, name, gizmo, on_edit)
        self.mesh = pv.lines_from_points(gizmo.points)
        self._add_mesh(self.mesh, line_width=3)
        if gizmo.edit:
            self._add_handle(gizmo.points[-1], gizmo.edit)

    def fits(self, gizmo: Gizmo) -> bool:
        return super().fits(gizmo) and isinstance(gizmo, LineGizmo) and gizmo.points.shape == self.gizmo.points.shape

    def update(self, gizmo: LineGizmo) -> None:
        self.gizmo = gizmo
        self._move(self.mesh, gizmo.points)
        if self.widget is not None:
            self._handle_at(gizmo.points[-1])


class BoxAdapter(GizmoAdapter):
    """A :class:`~engine.gizmos.BoxGizmo`: an outline, with a box widget whose faces
    drag when editable."""

    shape = BoxGizmo

    def __init__(self, plotter: pv.Plotter, name: str, gizmo: BoxGizmo, on_edit: EditCallback) -> None:
        super().__init__(plotter, name, gizmo, on_edit)
        self._bounds = gizmo.bounds
        self.mesh = pv.Box(bounds=self._bounds).outline()
        self._add_mesh(self.mesh, line_width=2)
        if gizmo.edit:
            self.widget = plotter.add_box_widget(
                self._box_moved,
                bounds=self._bounds,
                factor=1.0,
                rotation_enabled=False,
                color=style.GIZMO,
                interaction_event="end",
            )
            set_priority(self.widget, BOX_PRIORITY)

    def _box_moved(self, box: pv.PolyData) -> None:
        b = np.asarray(box.bounds, float)
        if np.allclose(b, self._bounds):  # pyvista calls back once on creation; nothing moved
            return
        lower_field, upper_field = self.gizmo.edit
        self.on_edit(self.name, {lower_field: b[0::2], upper_field: b[1::2]})

    def update(self, gizmo: BoxGizmo) -> None:
        self.gizmo = gizmo
        bounds = gizmo.bounds
        if bounds != self._bounds:  # edited in the panel or by a drag: move the handles too
            self._bounds = bounds
            self.mesh.copy_from(pv.Box(bounds=bounds).outline())
            if self.widget is not None:
                self.widget.PlaceWidget(bounds)


#: The adapter of each gizmo shape class (looked up along the shape's class hierarchy).
GIZMO_ADAPTERS: dict[type[Gizmo], type[GizmoAdapter]] = {a.shape: a for a in (PointAdapter, LineAdapter, BoxAdapter)}
