"""Constraint gizmos in the viewport: each constraint's shape drawn by its adapter.

Each enabled constraint describes itself with ``Constraint.gizmo()``, a frozen shape of
:mod:`engine.gizmos` (a point, a line, a box) or None. :func:`adapter_for` picks the
shape's adapter from :data:`~widgets.viewport.gizmo_adapters.GIZMO_ADAPTERS` along the
shape's class hierarchy and raises ``TypeError`` for a shape nobody registered, so a new
shape without an adapter fails the first time it is drawn instead of vanishing.

A constraint's adapter is kept while its shape :meth:`~GizmoAdapter.fits` (same class,
same edit fields...) and its geometry is moved in place; otherwise it is rebuilt.
"""

from __future__ import annotations

import pyvista as pv

from engine.gizmos import Gizmo
from widgets.viewport.gizmo_adapters import GIZMO_ADAPTERS, EditCallback, GizmoAdapter


def adapter_for(shape: type[Gizmo]) -> type[GizmoAdapter]:
    """The adapter class that draws ``shape`` (its own, or its nearest base class's).

    Raises
    ------
    TypeError
        When no class in ``shape``'s hierarchy has an adapter.
    """
    for cls in shape.__mro__:
        if cls in GIZMO_ADAPTERS:
            return GIZMO_ADAPTERS[cls]
    raise TypeError(
        f"no viewport adapter draws gizmo type {shape.__module__}.{shape.__qualname__}; "
        "register one in widgets.viewport.gizmo_adapters.GIZMO_ADAPTERS"
    )


class ConstraintGizmos:
    """All gizmos of the enabled constraints, keyed by constraint name."""

    def __init__(self, plotter: pv.Plotter, on_edit: EditCallback) -> None:
        self._plotter = plotter
        self._on_edit = on_edit
        self.items: dict[str, GizmoAdapter] = {}

    def update(self, gizmos: tuple[tuple[str, Gizmo | None], ...]) -> None:
        """Draw ``(constraint name, shape)`` pairs; None draws nothing for that constraint.

        Raises
        ------
        TypeError
            For a shape with no adapter (:func:`adapter_for`).
        """
        shown = {name: g for name, g in gizmos if g is not None}
        for name in [n for n in self.items if n not in shown]:
            self.items.pop(name).remove()
        for name, g in shown.items():
            item = self.items.get(name)
            if item is not None and item.fits(g):
                item.update(g)
                continue
            adapter = adapter_for(type(g))  # raises before the old item is taken down
            if item is not None:
                item.remove()
            self.items[name] = adapter(self._plotter, name, g, self._on_edit)

    def clear(self) -> None:
        for item in self.items.values():
            item.remove()
        self.items = {}
