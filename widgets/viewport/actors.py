"""Actors coloured straight from an RGB(A) array, with no Python filter in their pipeline.

``plotter.add_mesh(mesh, scalars=..., rgb=True)`` (and ``smooth_shading=True``) puts
pyvista's Python-implemented algorithms between the mesh and its mapper; they run again
whenever the mesh is modified, i.e. on every frame of a moving drawable, and bounds
queries such as ``ResetCameraClippingRange`` run them too (several ms per frame here).
Drawables that move every frame build their actor with :func:`direct_colour_actor`.
"""

from __future__ import annotations

from typing import Any

import pyvista as pv
import vtk


def direct_colour_actor(
    plotter: Any, mesh: pv.PolyData, array: str, cells: bool = False, name: str | None = None, **props: float
) -> vtk.vtkActor:
    """Add ``mesh`` coloured by its uint8 ``array`` (RGB or RGBA per point, or per cell
    with ``cells``); ``props`` are ``vtkProperty`` setters (``line_width=3`` calls
    ``SetLineWidth(3)``, ``lighting=False`` calls ``SetLighting(False)``). Normals, when
    wanted, are the mesh's active point normals. Not pickable; the camera is not reset."""
    mapper = vtk.vtkPolyDataMapper()
    mapper.SetInputData(mesh)
    if cells:
        mapper.SetScalarModeToUseCellFieldData()
    else:
        mapper.SetScalarModeToUsePointFieldData()
    mapper.SelectColorArray(array)
    mapper.SetColorModeToDirectScalars()
    mapper.ScalarVisibilityOn()
    actor = vtk.vtkActor()
    actor.SetMapper(mapper)
    actor.PickableOff()
    prop = actor.GetProperty()
    for key, value in props.items():
        getattr(prop, "Set" + "".join(part.capitalize() for part in key.split("_")))(value)
    plotter.add_actor(actor, reset_camera=False, name=name, render=False)
    return actor
