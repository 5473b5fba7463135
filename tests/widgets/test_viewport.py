"""The VTK viewport under Xvfb: in-place drawing, dragging a target, visible skeleton."""

from __future__ import annotations

import numpy as np
import pytest

from widgets.viewport import Viewport

pytestmark = pytest.mark.gui


@pytest.fixture
def viewport(qtbot):
    v = Viewport()
    v.resize(640, 480)
    v.show()
    qtbot.waitExposed(v)
    yield v
    v.close()


def orange_fraction(img: np.ndarray) -> float:
    """Share of pixels with the reconstruction's hue (shading changes its brightness)."""
    r, g, b = (img[..., i].astype(int) for i in range(3))
    return float(np.mean((r > 120) & (g > 60) & (g < r - 40) & (b < g - 20)))


def test_snapshot_updates_geometry_in_place_and_is_visible(viewport, fake_snapshot):
    snap = fake_snapshot()
    viewport.show_snapshot(snap)
    mesh = viewport.reconstruction.mesh
    viewport.show_snapshot(fake_snapshot(seq=2, positions=snap.positions + [0, 0, 0.1]))
    assert viewport.reconstruction.mesh is mesh
    assert np.allclose(mesh.points[0], snap.positions[0] + [0, 0, 0.1])
    img = viewport.plotter.screenshot(return_img=True)
    assert orange_fraction(img) > 0.003


def test_dragging_a_sensor_emits_its_new_position(viewport, qtbot, fake_snapshot):
    viewport.show_snapshot(fake_snapshot())
    widget = viewport.sensors.widgets["root"]
    with qtbot.waitSignal(viewport.targetDragged) as sig:
        widget.InvokeEvent("StartInteractionEvent")
        widget.SetCenter(0.1, 0.2, 1.3)
        widget.InvokeEvent("InteractionEvent")
        widget.InvokeEvent("EndInteractionEvent")
    assert sig.args[0] == "root" and np.allclose(sig.args[1], [0.1, 0.2, 1.3])


def test_gizmos_follow_constraints(viewport, fake_snapshot):
    gizmos = (("pin", {"type": "point", "position": [0, 0, 1], "edit": "target"}),
              ("bounds", {"type": "box", "min": [-1, -1, 0], "max": [1, 1, 2]}),
              ("look", {"type": "line", "start": [0, 0, 1.6], "end": [0, -2, 1.6]}))  # fmt: skip
    viewport.show_snapshot(fake_snapshot(gizmos=gizmos))
    assert set(viewport.gizmos.items) == {"pin", "bounds", "look"}
    viewport.show_snapshot(fake_snapshot(seq=2, gizmos=gizmos[1:]))
    assert set(viewport.gizmos.items) == {"bounds", "look"}
