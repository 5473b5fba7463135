"""Skeleton drawable: bones as shaded tubes and joints as spheres, updated in place."""

from __future__ import annotations

import numpy as np
import pyvista as pv

from engine import skeleton as sk


def _bones_polydata(positions: np.ndarray) -> pv.PolyData:
    lines = np.array([[2, p, j] for j, p in enumerate(sk.PARENTS) if p >= 0]).ravel()
    return pv.PolyData(np.asarray(positions, float), lines=lines)


class SkeletonActor:
    """One skeleton in the scene (reconstruction, ground truth or a method's ghost).

    The points of a single 22-point polydata are rewritten every frame; the two actors
    (bones, joints) share it, so a frame costs one array copy and no new geometry.

    Parameters
    ----------
    plotter : pyvista.Plotter
        Where to draw.
    color : str
        Hex colour.
    opacity : float
        1 for the main pose, lower for ghosts.
    bone_width, joint_size : float
        Pixels (tubes and spheres are screen-space impostors).
    """

    def __init__(
        self,
        plotter: pv.Plotter,
        color: str,
        opacity: float = 1.0,
        bone_width: float = 7.0,
        joint_size: float = 12.0,
        name: str = "skeleton",
    ) -> None:
        self.mesh = _bones_polydata(sk.Skeleton.canonical().rest_positions())
        common = dict(color=color, opacity=opacity, pickable=False, reset_camera=False, lighting=True)
        self.bones = plotter.add_mesh(
            self.mesh,
            style="wireframe",
            line_width=bone_width,
            render_lines_as_tubes=True,
            name=f"{name}-bones",
            **common,
        )
        self.joints = plotter.add_mesh(
            self.mesh,
            style="points",
            point_size=joint_size,
            render_points_as_spheres=True,
            name=f"{name}-joints",
            **common,
        )
        self.visible = True

    def update(self, positions: np.ndarray | None) -> None:
        """Move the joints to ``positions`` (22, 3) metres; None hides the skeleton."""
        if positions is None or not np.all(np.isfinite(positions)):
            self.set_visible(False)
            return
        pts = self.mesh.GetPoints()
        self.mesh.points[:] = positions
        pts.Modified()
        self.set_visible(True)

    def set_visible(self, visible: bool) -> None:
        if visible != self.visible:
            self.visible = visible
            self.bones.SetVisibility(visible)
            self.joints.SetVisibility(visible)

    def remove(self, plotter: pv.Plotter) -> None:
        plotter.remove_actor([self.bones, self.joints], render=False)
