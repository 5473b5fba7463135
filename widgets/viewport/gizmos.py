"""Constraint gizmos: points, boxes (bounds) and lines (distance, look-at) in the viewport.

Each enabled constraint describes itself with ``Constraint.gizmo()``, a plain dict:

* ``{"type": "point", "position": (3,)}`` - a target; a sphere widget when editable
* ``{"type": "box", "min": (3,), "max": (3,)}`` - bounds; a box widget when editable
* ``{"type": "line", "points": (N, 3)}`` (or ``"start"``/``"end"``) - distance, look-at

A point may carry a ``"label"`` (drawn beside it, e.g. the joint a pin holds) and an
``"anchor"`` (3,): a thin line from the anchor (the joint now) to the point shows the
pull. An optional ``"edit"`` key names the constraint field(s) a drag writes back (a string
for a point or for a line's last point, such as a look-at target; a pair
``(min_field, max_field)`` for a box). Gizmos are rebuilt only when
the set of constraints changes; otherwise their geometry is moved in place.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np
import pyvista as pv
import vtk

from widgets import style

EditCallback = Callable[[str, dict[str, Any]], None]


def _vec(g: dict, *keys: str) -> np.ndarray | None:
    for k in keys:
        if k in g and g[k] is not None:
            return np.asarray(g[k], float)
    return None


def _line_points(g: dict) -> np.ndarray:
    pts = _vec(g, "points")
    if pts is None:
        pts = np.array([_vec(g, "start", "from", "a"), _vec(g, "end", "to", "b")], float)
    return pts.reshape(-1, 3)


class _Gizmo:
    def __init__(self, plotter: pv.Plotter, name: str, g: dict, on_edit: EditCallback) -> None:
        self.plotter, self.name, self.on_edit = plotter, name, on_edit
        self.kind = g.get("type", "")
        self.actors: list = []
        self.widget = None
        self.dragging = False
        self.edit = edit = g.get("edit")
        self._bounds = self._box_bounds(g) if self.kind == "box" else None
        self.label = self.tether = None
        if self.kind == "point":
            p = _vec(g, "position", "center", "target")
            if edit:
                self._add_handle(plotter, p)
            else:
                self.mesh = pv.PolyData(p[None])
                self.actors.append(plotter.add_mesh(self.mesh, color=style.GIZMO, point_size=14,
                                                    render_points_as_spheres=True, reset_camera=False))  # fmt: skip
            self._add_decorations(plotter, g, p)
        elif self.kind == "box":
            self.mesh = pv.Box(bounds=self._bounds).outline()
            self.actors.append(plotter.add_mesh(self.mesh, color=style.GIZMO, line_width=2, reset_camera=False))
            if edit:
                self.widget = plotter.add_box_widget(
                    self._box_moved, bounds=self._bounds, factor=1.0,
                    rotation_enabled=False, color=style.GIZMO, interaction_event="end",
                )  # fmt: skip
        elif self.kind == "line":
            pts = _line_points(g)
            self.mesh = pv.lines_from_points(pts)
            self.actors.append(plotter.add_mesh(self.mesh, color=style.GIZMO, line_width=3, reset_camera=False))
            if edit:  # the line's end is a handle (e.g. the point a look-at aims at)
                self._add_handle(plotter, pts[-1])

    def _add_handle(self, plotter: Any, center: np.ndarray) -> None:
        """A draggable sphere at ``center`` that writes the ``edit`` field back."""
        self.widget = plotter.add_sphere_widget(
            self._point_moved, center=tuple(center), radius=0.04, color=style.GIZMO,
            interaction_event="always", test_callback=False, style="wireframe",
        )  # fmt: skip
        self._track(self.widget)

    def _add_decorations(self, plotter: Any, g: dict, p: np.ndarray) -> None:
        """The point's label and the line tying it to its anchor, when it has them."""
        anchor = _vec(g, "anchor")
        if anchor is not None:
            self.tether = pv.lines_from_points(np.stack([anchor, p]))
            self.actors.append(plotter.add_mesh(self.tether, color=style.GIZMO, line_width=1,
                                                pickable=False, reset_camera=False))  # fmt: skip
        if g.get("label"):
            self.label = vtk.vtkBillboardTextActor3D()
            self.label.SetInput(str(g["label"]))
            self.label.SetPosition(*(p + [0.0, 0.0, 0.07]))
            prop = self.label.GetTextProperty()
            prop.SetFontSize(14)
            prop.SetColor(*(c / 255 for c in style.hex_to_rgb(style.GIZMO)))
            prop.SetJustificationToCentered()
            self.label.PickableOff()
            plotter.add_actor(self.label, reset_camera=False, render=False)
            self.actors.append(self.label)

    def _move_decorations(self, g: dict, p: np.ndarray) -> None:
        anchor = _vec(g, "anchor")
        if self.tether is not None and anchor is not None:
            self.tether.points[:] = np.stack([anchor, p])
            self.tether.GetPoints().Modified()
        if self.label is not None:
            self.label.SetPosition(*(p + [0.0, 0.0, 0.07]))

    @staticmethod
    def _box_bounds(g: dict) -> tuple[float, ...]:
        lo, hi = _vec(g, "min", "lower"), _vec(g, "max", "upper")
        return (lo[0], hi[0], lo[1], hi[1], lo[2], hi[2])

    def _track(self, widget: Any) -> None:
        widget.AddObserver("StartInteractionEvent", lambda *_: setattr(self, "dragging", True))
        widget.AddObserver("EndInteractionEvent", lambda *_: setattr(self, "dragging", False))

    def _point_moved(self, center: np.ndarray) -> None:
        if self.dragging:
            self.on_edit(self.name, {str(self.edit): np.asarray(center, float)})

    def _box_moved(self, box: pv.PolyData) -> None:
        b = np.asarray(box.bounds, float)
        if np.allclose(b, self._bounds):  # pyvista calls back once on creation; nothing moved
            return
        lo_field, hi_field = self.edit if isinstance(self.edit, (tuple, list)) else ("min", "max")
        self.on_edit(self.name, {lo_field: b[0::2], hi_field: b[1::2]})

    def update(self, g: dict) -> None:
        if self.kind == "point":
            p = _vec(g, "position", "center", "target")
            if self.widget is not None:
                if not self.dragging:
                    self.widget.SetCenter(*p)
                else:
                    p = np.asarray(self.widget.GetCenter(), float)
            else:
                self.mesh.points[:] = p[None]
                self.mesh.GetPoints().Modified()
            self._move_decorations(g, p)
        elif self.kind == "box":
            bounds = self._box_bounds(g)
            if bounds != self._bounds:  # edited in the panel or by a drag: move the handles too
                self._bounds = bounds
                self.mesh.copy_from(pv.Box(bounds=bounds).outline())
                if self.widget is not None:
                    self.widget.PlaceWidget(bounds)
        elif self.kind == "line":
            pts = _line_points(g)
            if pts.shape == self.mesh.points.shape:
                self.mesh.points[:] = pts
                self.mesh.GetPoints().Modified()
            if self.widget is not None and not self.dragging:
                self.widget.SetCenter(*pts[-1])

    def remove(self) -> None:
        if self.widget is not None:
            self.widget.Off()
        if self.actors:
            self.plotter.remove_actor(self.actors, render=False)


class ConstraintGizmos:
    """All gizmos of the enabled constraints, keyed by constraint name."""

    def __init__(self, plotter: pv.Plotter, on_edit: EditCallback) -> None:
        self._plotter = plotter
        self._on_edit = on_edit
        self.items: dict[str, _Gizmo] = {}
        self._layout: tuple = ()

    def update(self, gizmos: tuple[tuple[str, dict], ...]) -> None:
        """Draw ``(constraint name, gizmo dict)`` pairs; unknown or empty gizmos are skipped."""
        gizmos = tuple((n, g) for n, g in gizmos if g and g.get("type") in ("point", "box", "line"))
        layout = tuple((n, g["type"], bool(g.get("edit")), g.get("label"), "anchor" in g) for n, g in gizmos)
        try:
            if layout != self._layout:
                self.clear()
                self.items = {n: _Gizmo(self._plotter, n, g, self._on_edit) for n, g in gizmos}
                self._layout = layout
            else:
                for n, g in gizmos:
                    self.items[n].update(g)
        except (TypeError, ValueError, IndexError):  # a malformed gizmo is cosmetic: skip it
            self.clear()

    def clear(self) -> None:
        for item in self.items.values():
            item.remove()
        self.items, self._layout = {}, ()
