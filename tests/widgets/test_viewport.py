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


def test_ctrl_drag_on_a_joint_moves_it_on_a_camera_facing_plane(viewport, qtbot, fake_snapshot):
    snap = fake_snapshot()
    viewport.show_snapshot(snap)
    dragger = viewport.joints
    j = 17  # lwrist
    x, y = dragger._to_display(snap.positions[j : j + 1])[0]
    assert dragger.press(x + 3, y - 2) and dragger.joint == j
    with qtbot.waitSignal(viewport.jointDragged) as sig:
        dragger.move(x + 40, y)
    name, pos = sig.args
    cam = viewport.plotter.camera
    normal = np.asarray(cam.focal_point) - np.asarray(cam.position)
    assert name == "lwrist"
    assert abs((pos - snap.positions[j]) @ normal) < 1e-6  # stays on the plane
    assert np.linalg.norm(pos - snap.positions[j]) > 0.05
    assert not dragger.press(1, 1)  # far from every joint: the camera keeps the click


def test_plain_left_drag_still_rotates_the_camera(viewport, fake_snapshot):
    viewport.show_snapshot(fake_snapshot())
    iren = viewport.plotter.iren.interactor
    before = np.array(viewport.plotter.camera.position)
    w, h = viewport.plotter.ren_win.GetSize()
    iren.SetEventInformation(w // 2, h // 2, 0, 0)
    iren.InvokeEvent("LeftButtonPressEvent")
    iren.SetEventInformation(w // 2 + 80, h // 2, 0, 0)
    iren.InvokeEvent("MouseMoveEvent")
    iren.InvokeEvent("LeftButtonReleaseEvent")
    assert viewport.joints.joint is None
    assert np.linalg.norm(np.array(viewport.plotter.camera.position) - before) > 1e-3


def test_ctrl_press_on_a_joint_takes_the_drag_from_the_camera(viewport, qtbot, fake_snapshot):
    snap = fake_snapshot()
    viewport.show_snapshot(snap)
    x, y = (int(round(v)) for v in viewport.joints._to_display(snap.positions[13:14])[0])
    iren = viewport.plotter.iren.interactor
    before = np.array(viewport.plotter.camera.position)
    iren.SetEventInformation(x, y, 1, 0)  # ctrl held
    iren.InvokeEvent("LeftButtonPressEvent")
    with qtbot.waitSignal(viewport.jointDragged) as sig:
        iren.SetEventInformation(x, y + 30, 1, 0)
        iren.InvokeEvent("MouseMoveEvent")
    iren.InvokeEvent("LeftButtonReleaseEvent")
    assert sig.args[0] == "upperneck" and viewport.joints.joint is None
    assert np.allclose(viewport.plotter.camera.position, before)


def test_a_line_gizmo_with_an_edit_field_has_a_draggable_end(viewport, qtbot, fake_snapshot):
    """A look-at draws a line from the head to its target; the target end is a handle."""
    look = ("look", {"type": "line", "points": [[0, 0, 1.6], [0, -2, 1.6]], "edit": "target"})
    viewport.show_snapshot(fake_snapshot(gizmos=(look,)))
    widget = viewport.gizmos.items["look"].widget
    assert widget is not None and np.allclose(widget.GetCenter(), [0, -2, 1.6])
    with qtbot.waitSignal(viewport.gizmoEdited) as sig:
        widget.InvokeEvent("StartInteractionEvent")
        widget.SetCenter(1.0, -2.0, 1.5)
        widget.InvokeEvent("InteractionEvent")
        widget.InvokeEvent("EndInteractionEvent")
    assert sig.args[0] == "look" and np.allclose(sig.args[1]["target"], [1.0, -2.0, 1.5])
    moved = ("look", {**look[1], "points": [[0, 0, 1.6], [1.0, -2.0, 1.5]]})
    viewport.show_snapshot(fake_snapshot(seq=2, gizmos=(moved,)))
    assert np.allclose(viewport.gizmos.items["look"].mesh.points[-1], [1.0, -2.0, 1.5])


def test_box_gizmo_drags_and_follows_edits_made_elsewhere(viewport, qtbot, fake_snapshot):
    import pyvista as pv

    edits = []
    viewport.gizmoEdited.connect(lambda n, ch: edits.append((n, ch)))
    box = {"type": "box", "min": [-1, -1, 0], "max": [1, 1, 2], "edit": ("box_min", "box_max")}
    viewport.show_snapshot(fake_snapshot(gizmos=(("bounds", box),)))
    assert edits == []  # building the box widget is not an edit
    gizmo = viewport.gizmos.items["bounds"]
    with qtbot.waitSignal(viewport.gizmoEdited) as sig:  # the user drags a face of the box
        gizmo.widget.PlaceWidget((-1, 1.5, -1, 1, 0, 2))
        gizmo.widget.InvokeEvent("EndInteractionEvent")
    assert sig.args[0] == "bounds" and np.allclose(sig.args[1]["box_max"], [1.5, 1, 2])
    viewport.show_snapshot(fake_snapshot(seq=2, gizmos=(("bounds", {**box, "max": [2, 1, 2]}),)))
    assert viewport.gizmos.items["bounds"] is gizmo  # moved in place, not rebuilt
    handles = pv.PolyData()
    gizmo.widget.GetPolyData(handles)
    assert np.allclose(handles.bounds[:2], [-1, 2]) and np.allclose(gizmo.mesh.bounds[:2], [-1, 2])


def test_three_dof_sensors_get_no_orientation_axes(viewport, fake_snapshot):
    snap = fake_snapshot(target_rotations=np.tile([np.sqrt(0.5), np.sqrt(0.5), 0, 0], (2, 1)))
    viewport.oriented = frozenset({"root"})  # lwrist is a 3-DoF tracker here
    viewport.show_snapshot(snap)
    tips = viewport.sensors._axes_mesh.points.reshape(2, 3, 2, 3)
    lengths = np.linalg.norm(tips[:, :, 1] - tips[:, :, 0], axis=-1)
    assert np.allclose(lengths[0], 0.12) and np.allclose(lengths[1], 0.0)


def test_ghosts_get_their_own_colour_and_follow_the_ghosts_toggle(viewport, fake_snapshot):
    snap = fake_snapshot()
    ik = snap.positions + [1.0, 0, 0]
    viewport.show_snapshot(fake_snapshot(seq=2, ghosts={"ik": ik}))
    ghost = viewport.ghosts["ik"]
    assert ghost.visible and np.allclose(ghost.mesh.points, ik)
    colour = ghost.bones.GetProperty().GetColor()
    assert not np.allclose(colour, viewport.reconstruction.bones.GetProperty().GetColor())
    assert not np.allclose(colour, viewport.ground_truth.bones.GetProperty().GetColor())
    viewport.show_ghosts = False
    viewport.show_snapshot(fake_snapshot(seq=3, ghosts={"ik": ik}))
    assert not ghost.visible
    viewport.show_ghosts = True
    viewport.show_snapshot(fake_snapshot(seq=4, ghosts={"ik": ik}))
    assert ghost.visible
    viewport.show_snapshot(fake_snapshot(seq=5))  # the method left the ghost list
    assert not ghost.visible


def test_follow_camera_glides_with_the_hips_and_holds_still_when_off(viewport, fake_snapshot):
    import time

    snap = fake_snapshot()
    moved = snap.positions + [2.0, 0, 0]
    focus_x = viewport.plotter.camera.focal_point[0]
    viewport._followed_at = time.monotonic()
    viewport.show_snapshot(fake_snapshot(seq=2, positions=moved))  # ~no time passed: barely moves
    assert viewport.plotter.camera.focal_point[0] - focus_x < 0.5
    for seq in range(3, 6):
        viewport._followed_at = time.monotonic() - 0.5  # as if half a second passed per redraw
        viewport.show_snapshot(fake_snapshot(seq=seq, positions=moved))
    cam = viewport.plotter.camera
    assert cam.focal_point[0] == pytest.approx(moved[0, 0], abs=0.01)
    offset = np.subtract(cam.position, cam.focal_point)
    viewport.follow = False
    viewport._followed_at = time.monotonic() - 1.0
    viewport.show_snapshot(fake_snapshot(seq=9, positions=moved + [3.0, 0, 0]))
    assert cam.focal_point[0] == pytest.approx(moved[0, 0], abs=0.01)
    assert np.allclose(np.subtract(cam.position, cam.focal_point), offset)  # the user's angle is kept
