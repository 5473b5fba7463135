"""Real mouse presses where the viewport's handles overlap: a point handle or a tracker
target inside an editable box is grabbed before the box, whose faces cover it on screen;
the box is still dragged by its own faces."""

from __future__ import annotations

import numpy as np
import pytest

from engine.gizmos import BoxGizmo, PointGizmo
from tests.app.gui_helpers import mouse_drag, pixel_of
from widgets.viewport import Viewport

pytestmark = pytest.mark.gui
BOX = ("bounds", BoxGizmo([-0.5, -0.5, 0.5], [0.5, 0.5, 1.8], edit=("box_min", "box_max")))
PIN = ("pin", PointGizmo([0.2, -0.1, 1.2], edit="position", label="pin"))


def box_bounds(v: Viewport) -> np.ndarray:
    import pyvista as pv

    handles = pv.PolyData()
    v.gizmos.items["bounds"].widget.GetPolyData(handles)
    return np.asarray(handles.bounds, float)


@pytest.mark.parametrize("order", ["box first", "pin first"])
def test_a_point_handle_inside_a_box_drags_the_point(viewport, fake_snapshot, order):
    edits = []
    viewport.gizmoEdited.connect(lambda n, ch: edits.append((n, ch)))
    viewport.show_snapshot(fake_snapshot(gizmos=(BOX, PIN) if order == "box first" else (PIN, BOX)))
    x, y = pixel_of(viewport, PIN[1].position)
    mouse_drag(viewport, (x, y), (x + 40, y - 30))
    assert edits and {n for n, _ in edits} == {"pin"}, "only the pin was edited"
    assert np.linalg.norm(edits[-1][1]["position"] - PIN[1].position) > 0.05
    assert np.allclose(box_bounds(viewport), [-0.5, 0.5, -0.5, 0.5, 0.5, 1.8])  # the box did not move


def test_a_tracker_target_inside_a_box_drags_the_target(viewport, fake_snapshot):
    dragged = []
    viewport.targetDragged.connect(lambda j, p: dragged.append((j, p)))
    edits = []
    viewport.gizmoEdited.connect(lambda n, ch: edits.append(n))
    viewport.show_snapshot(fake_snapshot(gizmos=(BOX,)))  # the root's target (0, 0, 1) is inside
    x, y = pixel_of(viewport, [0.0, 0.0, 1.0])
    mouse_drag(viewport, (x, y), (x + 40, y - 30))
    assert dragged and dragged[-1][0] == "root" and np.linalg.norm(dragged[-1][1] - [0, 0, 1.0]) > 0.05
    assert edits == [] and np.allclose(box_bounds(viewport), [-0.5, 0.5, -0.5, 0.5, 0.5, 1.8])


def test_the_box_still_drags_by_its_face_handle(viewport, fake_snapshot):
    edits = []
    viewport.gizmoEdited.connect(lambda n, ch: edits.append((n, ch)))
    viewport.show_snapshot(fake_snapshot(gizmos=(BOX, PIN)))
    x, y = pixel_of(viewport, [0.0, -0.5, 1.15])  # the front face's handle, off the pin
    mouse_drag(viewport, (x, y), (x + 30, y + 20))
    assert edits and edits[-1][0] == "bounds"
    assert not np.allclose(box_bounds(viewport), [-0.5, 0.5, -0.5, 0.5, 0.5, 1.8])
