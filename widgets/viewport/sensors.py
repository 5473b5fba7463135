"""Sensor drawable: a sphere per tracker target plus its orientation axes, draggable.

All targets are one mesh (a sphere copied to each target, moved in place with numpy)
and one actor; the axes (x red, y green, z blue, 12 cm; they show the tracker's
rotation for 6-DoF sensors) are a second. A VTK sphere widget per target costs a
pipeline run and a draw call per target on every frame (about 5 ms of a 20 ms draw on
Mesa's software rasterizer), so the targets are grabbed by screen position instead:
:meth:`SensorMarkers.pick` finds the target under the mouse, the viewport's dragger
(:mod:`widgets.viewport.picking`) moves it on a camera-facing plane, and while one is
dragged incoming snapshots do not move it.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
import pyvista as pv

from engine.kinematics.quat_np import rotate
from widgets import style
from widgets.viewport.actors import direct_colour_actor

AXIS_LENGTH = 0.12  # metres
PICK_MARGIN_PX = 4.0  # a press this far outside a target's outline still grabs it
_AXIS_RGB = np.array([[230, 60, 60], [60, 200, 80], [70, 130, 255]], np.uint8)
_STATE_COLOURS = {"connected": style.SENSOR, "lost": style.SENSOR_LOST, "dragged": style.GIZMO}


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

    def __init__(self, plotter: pv.Plotter, on_drag: Callable[[str, np.ndarray], None], radius: float = 0.045) -> None:
        self._plotter = plotter
        self._on_drag = on_drag
        self.radius = radius
        self._sphere = pv.Sphere(radius=radius, theta_resolution=16, phi_resolution=16)
        self.joints: tuple[str, ...] = ()
        self.positions = np.zeros((0, 3))
        self.dragging: str | None = None
        self._states: tuple[str, ...] = ()
        self.mesh: pv.PolyData | None = None
        self._actor = None
        self._axes_mesh: pv.PolyData | None = None
        self._axes_actor = None
        #: False while another view of the character is drawn (a played bake): targets hidden.
        self.shown = True

    def set_shown(self, shown: bool) -> None:
        """Show or hide every target sphere and axis (not drawn until the next render)."""
        self.shown = bool(shown)
        if self._actor is not None:
            self._actor.SetVisibility(self.shown and len(self.joints) > 0)
        if self._axes_actor is not None:
            self._axes_actor.SetVisibility(self.shown)

    def _rebuild(self, joints: tuple[str, ...]) -> None:
        """New meshes for a new set of targets (a preset change), drawn in place after."""
        for actor in (self._actor, self._axes_actor):
            if actor is not None:
                self._plotter.remove_actor(actor, render=False)
        n, m = len(joints), self._sphere.n_points
        faces = self._sphere.faces.reshape(-1, 4)  # triangles: (3, a, b, c)
        tiled = np.concatenate([faces + [0, k * m, k * m, k * m] for k in range(max(n, 1))])
        self.mesh = pv.PolyData(np.tile(self._sphere.points, (max(n, 1), 1)), faces=tiled.ravel())
        self.mesh.point_data["Normals"] = np.tile(self._sphere.point_normals, (max(n, 1), 1))
        self.mesh.point_data.active_normals_name = "Normals"  # translation keeps them
        self.mesh.point_data["rgb"] = np.zeros((self.mesh.n_points, 3), np.uint8)
        self._actor = direct_colour_actor(self._plotter, self.mesh, "rgb", name="sensor-targets")
        self._actor.SetVisibility(n > 0 and self.shown)
        pts = np.zeros((max(n, 1) * 6, 3))
        lines = np.hstack([[2, i, i + 1] for i in range(0, len(pts), 2)])
        self._axes_mesh = pv.PolyData(pts, lines=lines)
        self._axes_mesh.cell_data["rgb"] = np.tile(_AXIS_RGB, (max(n, 1), 1))
        self._axes_actor = direct_colour_actor(
            self._plotter, self._axes_mesh, "rgb", cells=True, name="sensor-axes", line_width=3
        )
        self._axes_actor.SetVisibility(self.shown)
        self.joints, self._states = joints, ()
        self.positions = np.zeros((n, 3))
        if self.dragging not in joints:
            self.dragging = None

    def update(
        self,
        joints: tuple[str, ...],
        positions: np.ndarray,
        rotations: np.ndarray,
        connected: np.ndarray,
        show_axes: tuple[bool, ...] | None = None,
    ) -> None:
        """Place the targets: ``positions`` (S, 3) m, ``rotations`` (S, 4), ``connected`` (S,)."""
        if tuple(joints) != self.joints or self.mesh is None:
            self._rebuild(tuple(joints))
        if not joints:
            return
        positions = np.array(positions, float)
        if self.dragging is not None:  # the dragged target stays under the mouse
            i = self.joints.index(self.dragging)
            positions[i] = self.positions[i]
        self.positions = positions
        self._set_states(
            tuple("dragged" if j == self.dragging else "connected" if c else "lost" for j, c in zip(joints, connected))
        )
        self._place()
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

    def _place(self) -> None:
        """Move the sphere copies to ``self.positions`` (one array write)."""
        m = self._sphere.n_points
        pts = self.mesh.points.reshape(len(self.joints), m, 3)
        pts[:] = self._sphere.points[None] + self.positions[:, None, :]
        self.mesh.GetPoints().Modified()

    def _set_states(self, states: tuple[str, ...]) -> None:
        """Colour each target by its state (only when a state changed)."""
        if states == self._states:
            return
        self._states = states
        rgb = np.array([style.hex_to_rgb(_STATE_COLOURS[s]) for s in states], np.uint8)
        self.mesh.point_data["rgb"][:] = np.repeat(rgb, self._sphere.n_points, axis=0)
        self.mesh.point_data["rgb"].Modified()

    # -- dragging (driven by widgets.viewport.picking.JointDragger) ------------------
    def pick(self, to_display: Callable[[np.ndarray], np.ndarray], x: float, y: float) -> tuple[str, np.ndarray] | None:
        """The target whose sphere covers display pixel (x, y), nearest first, and its
        position; None when the press misses every target. ``to_display`` maps world
        points (N, 3) to display pixels (N, 2)."""
        if not self.joints:
            return None
        centres = to_display(self.positions)
        # the on-screen radius of each sphere: project a point one radius away, sideways
        cam = self._plotter.camera
        up = np.asarray(cam.up, float)
        up /= np.linalg.norm(up) or 1.0
        edges = to_display(self.positions + self.radius * up)
        radius_px = np.linalg.norm(edges - centres, axis=1) + PICK_MARGIN_PX
        dist = np.linalg.norm(centres - [x, y], axis=1)
        hits = np.flatnonzero(dist <= radius_px)
        if hits.size == 0:
            return None
        i = int(hits[np.argmin(dist[hits])])
        return self.joints[i], self.positions[i].copy()

    def begin_drag(self, joint: str) -> None:
        self.dragging = joint
        self._set_states(tuple("dragged" if j == joint else s for j, s in zip(self.joints, self._states)))

    def drag(self, joint: str, position: np.ndarray) -> bool:
        """Move the dragged target's sphere to ``position`` and report it; False (nothing
        moved) when the target went away during its drag (cleared, undone, another frame)."""
        if joint not in self.joints:
            self.dragging = None
            return False
        i = self.joints.index(joint)
        self.positions[i] = position
        self._place()
        self._on_drag(joint, np.asarray(position, float))
        return True

    def end_drag(self) -> None:
        self.dragging = None  # the next snapshot recolours it

    def clear(self) -> None:
        """Forget the targets (the actors go with the plotter)."""
        self.dragging = None
