"""Rotation handles: three rings about a joint (about world X red, Y green, Z blue) and a
facing arrow, for turning a joint by dragging a ring rather than by a modifier key.

A press within :data:`RING_PICK_PX` of a ring's drawn circle grabs it, unless it lands on
the hub (the joint or target sphere the rings surround, :data:`HUB_RADIUS`): a ring seen
edge-on is a line through its centre, and a press on the sphere there is meant for the
sphere (the dragger also leaves a press to any other joint nearer than the circle:
:meth:`widgets.viewport.picking.JointDragger.press_ring`). Every mouse move
then gives the angle swept about the ring's axis since the press (the mouse ray meets
the ring's plane; radians, right-handed about the axis), in whole degrees or, with Ctrl
held, in 5-degree steps, which the dragger reports to its owner. The ring about +Z turns a joint the way a head turns to look left or right.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
import pyvista as pv

#: A press this close to a ring's circle grabs it, pixels.
RING_PICK_PX = 8.0
#: The hub of the rings: a press this close to their centre on screen (metres, the
#: target sphere's 4.5 cm and a margin; at least :data:`HUB_MIN_PX` pixels, a joint's pick
#: radius) is left to the sphere or joint there.
HUB_RADIUS = 0.055
HUB_MIN_PX = 14.0
#: A ring turns by whole degrees, and by :data:`COARSE_STEP_DEG` with Ctrl held: a
#: joint's rings seen from above span a few dozen pixels, about 2.5 degrees a pixel, so
#: the unrounded angle goes from 59.2 to 61.7 in one pixel and a head turned exactly 60
#: degrees would be luck.
STEP_DEG = 1.0
COARSE_STEP_DEG = 5.0
#: Points per ring (drawn and picked).
RING_POINTS = 64
AXES = np.eye(3)
#: The facing arrow starts this far in front of the head (outside its rings), metres.
ARROW_AT = 0.14
COLOURS = ("#ff4d4d", "#5ad35a", "#4d8dff")


def circle(center: np.ndarray, axis: np.ndarray, radius: float, n: int = RING_POINTS) -> np.ndarray:
    """``n`` points ``(n, 3)`` of the circle of ``radius`` metres about ``axis`` through ``center``."""
    axis = np.asarray(axis, float) / np.linalg.norm(axis)
    u = np.cross(axis, [0.0, 0.0, 1.0] if abs(axis[2]) < 0.9 else [1.0, 0.0, 0.0])
    u /= np.linalg.norm(u)
    v = np.cross(axis, u)
    t = np.linspace(0.0, 2 * np.pi, n, endpoint=False)
    return np.asarray(center, float) + radius * (np.cos(t)[:, None] * u + np.sin(t)[:, None] * v)


def swept_angle(center: np.ndarray, axis: np.ndarray, start: np.ndarray, now: np.ndarray) -> float:
    """Signed angle (radians) about ``axis`` from ``start - center`` to ``now - center``
    (both projected on the plane normal to ``axis``)."""
    axis = np.asarray(axis, float) / np.linalg.norm(axis)
    a = np.asarray(start, float) - center
    b = np.asarray(now, float) - center
    a -= (a @ axis) * axis
    b -= (b @ axis) * axis
    return float(np.arctan2(np.cross(a, b) @ axis, a @ b))


def snapped(angle: float, coarse: bool = False) -> float:
    """``angle`` radians rounded to the nearest :data:`STEP_DEG` degrees, or
    :data:`COARSE_STEP_DEG` when ``coarse``; radians."""
    step = np.radians(COARSE_STEP_DEG if coarse else STEP_DEG)
    return float(np.round(angle / step) * step)


class RotationRings:
    """The rings (hidden until :meth:`show`) and the facing arrow of one plotter."""

    def __init__(self, plotter: pv.Plotter) -> None:
        self._plotter = plotter
        self.center = np.zeros(3)
        self.radius = 0.12
        self.visible = False
        self.shown: tuple[int, ...] = ()
        self.meshes, self.actors = [], []
        for k in range(3):
            pts = circle(self.center, AXES[k], self.radius)
            mesh = pv.PolyData(pts, lines=np.r_[RING_POINTS + 1, np.arange(RING_POINTS), 0])
            actor = plotter.add_mesh(
                mesh,
                color=COLOURS[k],
                style="wireframe",
                line_width=4,
                render_lines_as_tubes=True,
                pickable=False,
                reset_camera=False,
                name=f"ring-{k}",
            )
            actor.SetVisibility(False)
            self.meshes.append(mesh)
            self.actors.append(actor)
        # a cone pointing along -Y (the canonical front) from the origin, moved onto the head
        self._arrow_mesh = pv.Cone(
            center=(0, -ARROW_AT - 0.05, 0), direction=(0, -1, 0), height=0.1, radius=0.03, resolution=16
        )
        self._arrow_rest = self._arrow_mesh.points.copy()
        self.arrow = plotter.add_mesh(
            self._arrow_mesh, color="#f2f4f8", pickable=False, reset_camera=False, name="facing"
        )
        self.arrow.SetVisibility(False)
        # a drag: the axis grabbed, the world point of the press on its plane
        self.axis: int | None = None
        self._start = np.zeros(3)

    def show(self, center: np.ndarray, radius: float | None = None, axes: tuple[int, ...] = (0, 1, 2)) -> None:
        """Put the rings of ``axes`` about ``center (3,)`` metres (``radius`` metres,
        default kept); the others are hidden."""
        self.center = np.asarray(center, float).copy()
        if radius is not None:
            self.radius = float(radius)
        self.shown = tuple(axes)
        for k, mesh in enumerate(self.meshes):
            mesh.points[:] = circle(self.center, AXES[k], self.radius)
            mesh.GetPoints().Modified()
            self.actors[k].SetVisibility(k in self.shown)
        self.visible = True

    def hide(self) -> None:
        for a in self.actors:
            a.SetVisibility(False)
        self.visible = False
        self.axis = None

    def show_facing(self, origin: np.ndarray | None, direction: np.ndarray | None = None) -> None:
        """Draw the facing arrow at ``origin (3,)`` pointing along ``direction (3,)`` (None hides it)."""
        if origin is None or direction is None:
            self.arrow.SetVisibility(False)
            return
        d = np.asarray(direction, float)
        d /= max(np.linalg.norm(d), 1e-9)
        rest = np.array([0.0, -1.0, 0.0])
        axis = np.cross(rest, d)
        s, c = np.linalg.norm(axis), float(rest @ d)
        if s < 1e-9:
            r = np.eye(3) if c > 0 else np.diag([-1.0, -1.0, 1.0])
        else:
            k = axis / s
            kx = np.array([[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]])
            r = np.eye(3) + s * kx + (1 - c) * kx @ kx
        self._arrow_mesh.points[:] = self._arrow_rest @ r.T + np.asarray(origin, float)
        self._arrow_mesh.GetPoints().Modified()
        self.arrow.SetVisibility(True)

    # -- dragging ------------------------------------------------------------------
    def pick(self, to_display: Callable[[np.ndarray], np.ndarray], x: float, y: float) -> int | None:
        """The ring (0, 1, 2: about X, Y, Z) whose circle passes within
        :data:`RING_PICK_PX` of display pixel (x, y), the nearest; None if none."""
        if not self.visible or self.on_hub(to_display, x, y):
            return None
        best, hit = np.inf, None
        for k, mesh in enumerate(self.meshes):
            if k not in self.shown:
                continue
            screen = to_display(np.asarray(mesh.points))
            d = float(np.linalg.norm(screen - [x, y], axis=1).min())
            if d > RING_PICK_PX:
                continue
            # where rings cross, the one seen face-on wins over one seen edge-on (a line
            # through the joint, which a press meant for the other would also touch)
            spread = np.linalg.svd(screen - screen.mean(axis=0), compute_uv=False)
            edge_on = 1.0 - spread[-1] / max(spread[0], 1e-9)
            if d + RING_PICK_PX * edge_on < best:
                best, hit = d + RING_PICK_PX * edge_on, k
        return hit

    def distance(self, to_display: Callable[[np.ndarray], np.ndarray], axis: int, x: float, y: float) -> float:
        """How far display pixel (x, y) is from ring ``axis``'s drawn circle, pixels."""
        screen = to_display(np.asarray(self.meshes[axis].points))
        return float(np.linalg.norm(screen - [x, y], axis=1).min())

    def on_hub(self, to_display: Callable[[np.ndarray], np.ndarray], x: float, y: float) -> bool:
        """Whether display pixel (x, y) is on the rings' hub (see :data:`HUB_RADIUS`)."""
        up = np.asarray(self._plotter.camera.up, float)
        up /= np.linalg.norm(up) or 1.0
        centre, edge = to_display(np.stack([self.center, self.center + HUB_RADIUS * up]))
        hub_px = max(float(np.linalg.norm(edge - centre)), HUB_MIN_PX)
        return float(np.linalg.norm(centre - [x, y])) <= hub_px

    def begin(self, axis: int, ray: tuple[np.ndarray, np.ndarray]) -> None:
        """Grab ring ``axis`` where the mouse ray ``(origin, direction)`` meets its plane."""
        self.axis = axis
        self._start = self._on_plane(ray)

    def angle(self, ray: tuple[np.ndarray, np.ndarray], coarse: bool = False) -> float:
        """Radians swept about the grabbed ring's axis since :meth:`begin`, rounded to
        whole degrees (:data:`STEP_DEG`), or to :data:`COARSE_STEP_DEG` when ``coarse``
        (Ctrl held)."""
        if self.axis is None:
            return 0.0
        return snapped(swept_angle(self.center, AXES[self.axis], self._start, self._on_plane(ray)), coarse)

    def end(self) -> None:
        self.axis = None

    def _on_plane(self, ray: tuple[np.ndarray, np.ndarray]) -> np.ndarray:
        origin, direction = ray
        n = AXES[self.axis if self.axis is not None else 2]
        denom = float(direction @ n)
        if abs(denom) < 1e-9:  # the ray runs along the plane: its closest point to the centre
            t = float((self.center - origin) @ direction) / float(direction @ direction)
        else:
            t = float((self.center - origin) @ n) / denom
        return origin + t * direction

    def clear(self) -> None:
        for k in range(3):
            self._plotter.remove_actor(self.actors[k], render=False)
        self._plotter.remove_actor(self.arrow, render=False)
