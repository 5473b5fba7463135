"""Shaded body drawable: a capsule mannequin per bone plus a soft shadow on the floor.

All capsules live in one polydata built once; a frame rewrites its points and normals
from the joint positions (one vectorised numpy pass, no new geometry), so the body
costs about as much to draw as the stick figure. The shadow is a small disc of
vertex-alpha rings under the body: translucent, but only a few hundred pixels to blend,
unlike a filled floor.
"""

from __future__ import annotations

import numpy as np
import pyvista as pv

from engine import skeleton as sk
from engine.motion.mannequin import BONE_RADIUS  # the exported glTF body has the same build
from widgets.viewport.actors import direct_colour_actor

RING = 10  # vertices around a capsule
CAP_RINGS = 3  # latitude rings per hemisphere (the equator included)
SHADOW_RINGS = 6
SHADOW_SEGMENTS = 24
SHADOW_ALPHA = 0.45


def _unit_capsule() -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Template of one capsule: directions ``(T, 3)`` on the unit sphere (z along the
    bone), an ``along (T,)`` of 0 (parent end) or 1 (child end), and triangles ``(K, 3)``."""
    lat = np.concatenate([np.linspace(-np.pi / 2, 0, CAP_RINGS + 1)[1:], np.linspace(0, np.pi / 2, CAP_RINGS + 1)[:-1]])
    along = np.repeat(np.r_[np.zeros(CAP_RINGS), np.ones(CAP_RINGS)], RING)
    lon = np.linspace(0, 2 * np.pi, RING, endpoint=False)
    ring = np.stack(
        [
            np.outer(np.cos(lat), np.cos(lon)),
            np.outer(np.cos(lat), np.sin(lon)),
            np.repeat(np.sin(lat)[:, None], RING, 1),
        ],
        -1,
    ).reshape(-1, 3)
    dirs = np.vstack([ring, [[0, 0, -1.0]], [[0, 0, 1.0]]])
    along = np.r_[along, 0.0, 1.0]
    bottom, top = len(ring), len(ring) + 1
    tris = []
    rings = 2 * CAP_RINGS
    for r in range(rings - 1):
        for k in range(RING):
            a, b = r * RING + k, r * RING + (k + 1) % RING
            tris += [[a, b, b + RING], [a, b + RING, a + RING]]
    for k in range(RING):
        tris.append([bottom, (k + 1) % RING, k])
        last = (rings - 1) * RING
        tris.append([top, last + k, last + (k + 1) % RING])
    return dirs, along, np.array(tris)


def _frames(axis: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Two unit vectors ``(B, 3)`` perpendicular to each unit ``axis (B, 3)`` and each other."""
    helper = np.where(np.abs(axis[:, 2:3]) < 0.9, [[0.0, 0.0, 1.0]], [[1.0, 0.0, 0.0]])
    e1 = np.cross(axis, helper)
    e1 /= np.linalg.norm(e1, axis=1, keepdims=True)
    return e1, np.cross(axis, e1)


class BodyActor:
    """A shaded mannequin (one capsule per bone) and its floor shadow, moved in place.

    Parameters
    ----------
    plotter : pyvista.Plotter
        Where to draw.
    color : str
        Hex colour of the body.
    opacity : float
        1 for the main pose.
    name : str
        Actor name prefix.
    """

    def __init__(self, plotter: pv.Plotter, color: str, opacity: float = 1.0, name: str = "body") -> None:
        self.bones = np.array([(p, j) for j, p in enumerate(sk.PARENTS) if p >= 0])
        self.radius = np.array([BONE_RADIUS.get(sk.JOINT_NAMES[j], 0.05) for _, j in self.bones])
        self._dirs, self._along, tris = _unit_capsule()
        t, b = len(self._dirs), len(self.bones)
        faces = (tris[None] + (np.arange(b) * t)[:, None, None]).reshape(-1, 3)
        faces = np.hstack([np.full((len(faces), 1), 3), faces]).ravel()
        rest = sk.Skeleton.canonical().rest_positions()
        self.mesh = pv.PolyData(self._points(rest)[0], faces=faces)
        self.mesh.point_data["Normals"] = self._points(rest)[1]
        self.mesh.point_data.active_normals_name = "Normals"
        self.actor = plotter.add_mesh(
            self.mesh,
            color=color,
            opacity=opacity,
            smooth_shading=False,
            specular=0.25,
            pickable=False,
            reset_camera=False,
            name=f"{name}-mesh",
        )
        self.shadow_mesh = self._shadow_disc()
        self.shadow = direct_colour_actor(plotter, self.shadow_mesh, "rgba", name=f"{name}-shadow", lighting=False)
        self.visible = True

    def _points(self, positions: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Capsule vertices and normals ``(B * T, 3)`` for joint ``positions (22, 3)``."""
        a = positions[self.bones[:, 0]]
        d = positions[self.bones[:, 1]] - a
        length = np.linalg.norm(d, axis=1, keepdims=True)
        axis = d / np.maximum(length, 1e-9)
        axis[length[:, 0] < 1e-9] = (0.0, 0.0, 1.0)
        e1, e2 = _frames(axis)
        x, y, z = (self._dirs[None, :, i : i + 1] for i in range(3))
        normals = x * e1[:, None] + y * e2[:, None] + z * axis[:, None]  # (B, T, 3)
        centres = a[:, None] + self._along[None, :, None] * d[:, None]
        pts = centres + self.radius[:, None, None] * normals
        return pts.reshape(-1, 3), normals.reshape(-1, 3)

    @staticmethod
    def _shadow_disc() -> pv.PolyData:
        """Unit disc of rings whose alpha falls from the centre to 0 at the rim."""
        r = np.linspace(0, 1, SHADOW_RINGS + 1)[1:]
        ang = np.linspace(0, 2 * np.pi, SHADOW_SEGMENTS, endpoint=False)
        pts = np.vstack([[0.0, 0.0, 0.0]] + [np.c_[ri * np.cos(ang), ri * np.sin(ang), np.zeros_like(ang)] for ri in r])
        faces = []
        for k in range(SHADOW_SEGMENTS):
            faces += [3, 0, 1 + k, 1 + (k + 1) % SHADOW_SEGMENTS]
        for ring in range(SHADOW_RINGS - 1):
            o, n = 1 + ring * SHADOW_SEGMENTS, 1 + (ring + 1) * SHADOW_SEGMENTS
            for k in range(SHADOW_SEGMENTS):
                k2 = (k + 1) % SHADOW_SEGMENTS
                faces += [4, o + k, n + k, n + k2, o + k2]
        mesh = pv.PolyData(pts, faces=np.array(faces))
        alpha = SHADOW_ALPHA * (1.0 - np.r_[0.0, np.repeat(r, SHADOW_SEGMENTS)]) ** 1.5
        rgba = np.zeros((len(pts), 4), np.uint8)
        rgba[:, 3] = (255 * alpha).astype(np.uint8)
        mesh.point_data["rgba"] = rgba
        mesh.field_data["unit"] = pts.copy()  # the template the shadow is scaled from
        return mesh

    def update(self, positions: np.ndarray | None) -> None:
        """Pose the body at ``positions`` (22, 3) metres; None hides it."""
        if positions is None or not np.all(np.isfinite(positions)):
            self.set_visible(False)
            return
        positions = np.asarray(positions, float)
        pts, normals = self._points(positions)
        self.mesh.points[:] = pts
        self.mesh.point_data["Normals"][:] = normals
        self.mesh.GetPoints().Modified()
        self.mesh.GetPointData().GetNormals().Modified()
        # shadow: an ellipse over the joints' ground footprint, fainter as the body rises
        xy = positions[:, :2]
        centre = xy.mean(0)
        half = np.maximum(np.abs(xy - centre).max(0) + 0.12, 0.2)
        unit = self.shadow_mesh.field_data["unit"]
        sp = self.shadow_mesh.points
        sp[:, :2] = centre + unit[:, :2] * half
        sp[:, 2] = 0.002  # just above the grid, so the lines do not flicker through
        self.shadow_mesh.GetPoints().Modified()
        self.set_visible(True)

    def set_visible(self, visible: bool) -> None:
        if visible != self.visible:
            self.visible = visible
            self.actor.SetVisibility(visible)
            self.shadow.SetVisibility(visible)
