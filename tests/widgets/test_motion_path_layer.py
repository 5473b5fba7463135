"""The motion path drawable: lines broken at missing points, dots on marked and current
frames, and the same three polydata and actors however often it is redrawn."""

from __future__ import annotations

import time

import numpy as np
import pytest

from widgets.viewport.paths import MotionPathLayer, polylines

pytestmark = pytest.mark.gui


def test_a_missing_point_breaks_the_line():
    a = np.arange(15, dtype=float).reshape(5, 3)
    b = a.copy()
    b[2] = np.nan
    points, cells, owner = polylines([a, b])
    assert len(points) == 9 and list(owner) == [0] * 5 + [1] * 4
    assert list(cells) == [5, 0, 1, 2, 3, 4, 2, 5, 6, 2, 7, 8]
    assert len(polylines([np.full((3, 3), np.nan)])[0]) == 0


def test_paths_are_redrawn_in_place(viewport):
    layer: MotionPathLayer = viewport.paths
    renderer = viewport.plotter.renderer
    actors = renderer.GetActors().GetNumberOfItems()
    meshes = (layer.lines, layer.marks, layer.current)
    t = np.linspace(0, 1, 120)[:, None]
    wrist = np.hstack([t, 0 * t, 1 + 0.2 * np.sin(6 * t)])
    layer.show(
        10, {"lwrist": wrist, "lankle": wrist * [1, 1, 0.1]}, {"lwrist": "#ffd24d", "lankle": "#4dd0ff"}, [10, 70]
    )
    assert layer.shown and layer.lines.n_points == 240 and layer.marks.n_points == 4
    layer.at_frame(40)
    np.testing.assert_allclose(layer.current.points, [wrist[30], wrist[30] * [1, 1, 0.1]])
    viewport.plotter.render()
    colours = np.unique(np.asarray(layer.lines.point_data["rgb"]), axis=0)
    assert {tuple(c) for c in colours} == {(255, 210, 77), (77, 208, 255)}
    start = time.perf_counter()
    for f in range(10, 130):
        layer.at_frame(f)
    per_frame_ms = (time.perf_counter() - start) * 1000 / 120
    assert per_frame_ms < 2.0, f"{per_frame_ms:.2f} ms per frame"
    layer.at_frame(500)  # outside the path: no current dot
    assert layer.current.n_points == 0 and not layer.actors[2].GetVisibility()
    layer.show(0, {"lwrist": wrist[:50]}, {"lwrist": "#ffd24d"})
    assert layer.lines.n_points == 50 and layer.marks.n_points == 0
    layer.show(0, {}, {})
    assert not layer.shown
    assert (layer.lines, layer.marks, layer.current) == meshes
    assert renderer.GetActors().GetNumberOfItems() == actors, "no actor made or lost"
    layer.clear()  # the view closed: a late redraw (a queued recompute) draws nothing
    layer.show(10, {"lwrist": wrist}, {"lwrist": "#ffd24d"}, [10])
    layer.at_frame(20)
    assert not layer.shown
