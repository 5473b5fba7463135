"""Sensor drawable: one draggable sphere per tracker target plus its orientation axes.

Each target is a VTK sphere widget, so it can be grabbed and dragged with the mouse;
while the user drags one it is not moved by incoming snapshots. Axes (x red, y green,
z blue, 12 cm) show the tracker's rotation for 6-DoF sensors.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
import pyvista as pv

from engine.kinematics.quat_np import rotate
from widgets import style

AXIS_LENGTH = 0.12  # metres
_AXIS_RGB = np.array([[230, 60, 60], [60, 200, 80], [70, 130, 255]], np.uint8)


class SensorMarkers:
    """Targets of the active trackers.

    Parameters
    ----------
    plotter : pyvista.Plotter
        Where to draw.
    on_drag : callable
        ``on_drag(joint, position)`` with the new world position (3,) in metres.
    radius : float
        Sphere radius, metres.
    """

    def __init__(self, plotter: pv.Plotter, on_drag: Callable[[str, np.ndarray], None],
                 radius: float = 0.045) -> None:  # fmt: skip
        self._plotter = plotter
        self._on_drag = on_drag
        self._radius = radius
        self.joints: tuple[str, ...] = ()
        self.widgets: dict[str, object] = {}
        self.dragging: str | None = None
        self._axes_mesh: pv.PolyData | None = None
        self._axes_actor = None

    def _rebuild(self, joints: tuple[str, ...]) -> None:
        for wdg in self.widgets.values():
            wdg.Off()
        self._plotter.clear_sphere_widgets()
        self.widgets = {}
        for j in joints:
            wdg = self._plotter.add_sphere_widget(
                self._make_callback(j), center=(0.0, 0.0, 0.0), radius=self._radius,
                color=style.SENSOR, selected_color=style.GIZMO, theta_resolution=16,
                phi_resolution=16, interaction_event="always", test_callback=False,
            )  # fmt: skip
            wdg.AddObserver("StartInteractionEvent", lambda *_, j=j: setattr(self, "dragging", j))
            wdg.AddObserver("EndInteractionEvent", lambda *_: setattr(self, "dragging", None))
            self.widgets[j] = wdg
        if self._axes_actor is not None:
            self._plotter.remove_actor(self._axes_actor, render=False)
        n = len(joints)
        pts = np.zeros((max(n, 1) * 6, 3))
        lines = np.hstack([[2, i, i + 1] for i in range(0, len(pts), 2)])
        self._axes_mesh = pv.PolyData(pts, lines=lines)
        self._axes_mesh.cell_data["rgb"] = np.tile(_AXIS_RGB, (max(n, 1), 1))
        self._axes_actor = self._plotter.add_mesh(
            self._axes_mesh, scalars="rgb", rgb=True, line_width=3, pickable=False,
            reset_camera=False, name="sensor-axes",
        )  # fmt: skip
        self.joints = joints

    def _make_callback(self, joint: str) -> Callable:
        def moved(center: np.ndarray) -> None:
            if self.dragging == joint:
                self._on_drag(joint, np.asarray(center, float))

        return moved

    def update(self, joints: tuple[str, ...], positions: np.ndarray, rotations: np.ndarray,
               connected: np.ndarray, show_axes: tuple[bool, ...] | None = None) -> None:  # fmt: skip
        """Place the targets: ``positions`` (S, 3) m, ``rotations`` (S, 4), ``connected`` (S,)."""
        if tuple(joints) != self.joints:
            self._rebuild(tuple(joints))
        for i, j in enumerate(joints):
            wdg = self.widgets[j]
            if j != self.dragging:
                wdg.SetCenter(*positions[i])
            colour = style.SENSOR if connected[i] else style.SENSOR_LOST
            wdg.GetSphereProperty().SetColor(*(c / 255 for c in style.hex_to_rgb(colour)))
        if not joints:
            return
        axes = np.eye(3) * AXIS_LENGTH
        tips = rotate(rotations[:, None, :], axes[None]) + positions[:, None, :]  # (S, 3, 3)
        pts = np.empty((len(joints), 3, 2, 3))
        pts[:, :, 0] = positions[:, None, :]
        pts[:, :, 1] = tips
        if show_axes is not None:
            hidden = ~np.asarray(show_axes, bool)
            pts[hidden, :, 1] = pts[hidden, :, 0]
        self._axes_mesh.points[:] = pts.reshape(-1, 3)
        self._axes_mesh.GetPoints().Modified()

    def clear(self) -> None:
        for wdg in self.widgets.values():
            wdg.Off()
        self.widgets = {}
