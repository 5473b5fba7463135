"""Render an exported glTF file as an outside reader sees it: VTK's ``vtkGLTFReader``
(skinning and the animation applied on the CPU, not the studio's code) drawn with PyVista
off screen, a few frames of the clip side by side in one picture (docs/export.md).

    PYTHONPATH=. python scripts/gltf_snapshot.py MOTION.glb OUT.png [--times 0.5,2,3.5]

Meshes are coloured by the order of the scene's root nodes as the export writes them:
the main body, the comparison bodies (see-through), then the trackers' boxes.
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

COLOURS = ("#d08c66", "#5a8cd9", "#73bf66", "#d9bf4d")
TRACKER = "#19a0f2"


def meshes_at(path: Path, t: float) -> list[tuple[str, object]]:
    """``(root node name, deformed mesh)`` of every mesh of ``path`` at time ``t`` (seconds)."""
    import pyvista as pv
    import vtk

    reader = vtk.vtkGLTFReader()
    reader.SetFileName(str(path))
    reader.SetFrameRate(60)
    reader.ApplyDeformationsToGeometryOn()
    reader.UpdateInformation()
    for a in range(reader.GetNumberOfAnimations()):
        reader.EnableAnimation(a)
    reader.UpdateInformation()
    reader.UpdateTimeStep(t)
    out = []

    def walk(block, root):
        for i in range(block.n_blocks):
            child = block[i]
            if isinstance(child, pv.MultiBlock):
                walk(child, root)
            elif child is not None and child.n_points:
                out.append((root, child))

    scene = pv.wrap(reader.GetOutput())
    for i in range(scene.n_blocks):
        walk(scene[i], i)
    return out


def main() -> None:
    import pyvista as pv

    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("gltf", type=Path)
    ap.add_argument("out", type=Path)
    ap.add_argument("--times", default="0.5,2,3.5", help="seconds of the clip to draw, comma-separated")
    ap.add_argument("--size", default="1500,620")
    args = ap.parse_args()
    times = [float(t) for t in args.times.split(",")]
    w, h = (int(v) for v in args.size.split(","))
    pl = pv.Plotter(off_screen=True, shape=(1, len(times)), window_size=(w, h), border=False)
    for k, t in enumerate(times):
        pl.subplot(0, k)
        pl.set_background("#f4f4f2")
        meshes = meshes_at(args.gltf, t)
        bodies = sorted({r for r, m in meshes if m.n_points > 100})
        centre = np.zeros(3)
        for root, mesh in meshes:
            if mesh.n_points > 100:
                colour = COLOURS[bodies.index(root) % len(COLOURS)]
                main_body = root == bodies[0]
                pl.add_mesh(mesh, color=colour, smooth_shading=True, specular=0.2, opacity=1.0 if main_body else 0.4)
                if root == bodies[0]:
                    centre = np.array(mesh.center)
            else:
                pl.add_mesh(mesh, color=TRACKER)
        floor = pv.Plane(center=(centre[0], 0.0, centre[2]), direction=(0, 1, 0), i_size=4, j_size=4)
        pl.add_mesh(floor, color="#c8c8c4", opacity=0.6)
        pl.add_text(f"t = {t:g} s", font_size=10, color="black")
        pl.camera.focal_point = (centre[0], 0.9, centre[2])
        pl.camera.position = (centre[0] + 2.4, 1.6, centre[2] + 3.2)
        pl.camera.up = (0, 1, 0)
    args.out.parent.mkdir(parents=True, exist_ok=True)
    pl.screenshot(str(args.out))
    pl.close()
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
