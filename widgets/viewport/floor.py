"""Floor drawable: a static grid on z = 0 (metres), built once.

Lines only and opaque on purpose: a filled or translucent floor costs more than the
whole skeleton on software GL (llvmpipe under Xvfb).
"""

from __future__ import annotations

import numpy as np
import pyvista as pv

from widgets import style


class FloorGrid:
    """A ``size`` x ``size`` metre grid of ``spacing`` cells centred on the origin."""

    def __init__(self, plotter: pv.Plotter, size: float = 10.0, spacing: float = 0.5) -> None:
        n = int(size / spacing)
        ticks = np.linspace(-size / 2, size / 2, n + 1)
        segs = []
        for t in ticks:
            segs += [[t, -size / 2, 0], [t, size / 2, 0], [-size / 2, t, 0], [size / 2, t, 0]]
        pts = np.array(segs, float)
        lines = np.hstack([[2, i, i + 1] for i in range(0, len(pts), 2)])
        self.mesh = pv.PolyData(pts, lines=lines)
        self.grid = plotter.add_mesh(
            self.mesh, color=style.FLOOR, line_width=1, pickable=False, reset_camera=False, name="floor-grid"
        )
