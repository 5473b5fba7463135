"""The VTK viewport under Xvfb: in-place drawing, dragging a target, visible skeleton."""

from __future__ import annotations

import numpy as np
import pytest

from engine.gizmos import BoxGizmo, LineGizmo, PointGizmo

pytestmark = pytest.mark.gui


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
    """A plain left-drag on a target sphere moves it on a camera-facing plane; the camera
    stays, and snapshots arriving meanwhile do not pull the target back."""
    snap = fake_snapshot()
    viewport.show_snapshot(snap)
    x, y = (int(round(v)) for v in viewport.joints._to_display(snap.target_positions[1:2])[0])  # lwrist
    iren = viewport.plotter.iren.interactor
    before = np.array(viewport.plotter.camera.position)
    iren.SetEventInformation(x + 2, y - 2, 0, 0)
    iren.InvokeEvent("LeftButtonPressEvent")
    assert viewport.joints.target == "lwrist" and viewport.sensors.dragging == "lwrist"
    with qtbot.waitSignal(viewport.targetDragged) as sig:
        iren.SetEventInformation(x + 40, y, 0, 0)
        iren.InvokeEvent("MouseMoveEvent")
    name, pos = sig.args
    assert name == "lwrist" and np.linalg.norm(pos - snap.target_positions[1]) > 0.05
    viewport.show_snapshot(fake_snapshot(seq=2))  # the engine has not caught up yet
    i = viewport.sensors.joints.index("lwrist")
    assert np.allclose(viewport.sensors.positions[i], pos)
    iren.InvokeEvent("LeftButtonReleaseEvent")
    assert viewport.joints.target is None and viewport.sensors.dragging is None
    assert np.allclose(viewport.plotter.camera.position, before)


def test_sensor_targets_are_one_actor_moved_in_place(viewport, fake_snapshot):
    """A VTK sphere widget per target re-ran its sphere source and cost a draw call per
    target on every frame (~5 ms of a draw under software GL): one mesh, moved in place."""
    snap = fake_snapshot()
    viewport.show_snapshot(snap)
    sensors = viewport.sensors
    mesh = sensors.mesh
    viewport.show_snapshot(fake_snapshot(seq=2, target_positions=snap.target_positions + [0, 0, 0.2]))
    assert sensors.mesh is mesh and not viewport.plotter.widgets.sphere_widgets
    per = mesh.n_points // 2
    centre = mesh.points[per:].mean(axis=0)  # the second target's sphere
    assert np.allclose(centre, snap.target_positions[1] + [0, 0, 0.2], atol=1e-6)
    lost = mesh.point_data["rgb"][per]  # fake_snapshot: lwrist is not connected
    assert tuple(lost) != tuple(mesh.point_data["rgb"][0])


def test_a_press_off_every_target_leaves_the_camera_to_the_user(viewport, fake_snapshot):
    viewport.show_snapshot(fake_snapshot())
    assert viewport.sensors.pick(viewport.joints._to_display, 1, 1) is None


def test_gizmos_follow_constraints(viewport, fake_snapshot):
    gizmos = (
        ("pin", PointGizmo([0, 0, 1], edit="target")),
        ("bounds", BoxGizmo([-1, -1, 0], [1, 1, 2])),
        ("look", LineGizmo([[0, 0, 1.6], [0, -2, 1.6]])),
    )
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
    look = ("look", LineGizmo([[0, 0, 1.6], [0, -2, 1.6]], edit="target"))
    viewport.show_snapshot(fake_snapshot(gizmos=(look,)))
    widget = viewport.gizmos.items["look"].widget
    assert widget is not None and np.allclose(widget.GetCenter(), [0, -2, 1.6])
    with qtbot.waitSignal(viewport.gizmoEdited) as sig:
        widget.InvokeEvent("StartInteractionEvent")
        widget.SetCenter(1.0, -2.0, 1.5)
        widget.InvokeEvent("InteractionEvent")
        widget.InvokeEvent("EndInteractionEvent")
    assert sig.args[0] == "look" and np.allclose(sig.args[1]["target"], [1.0, -2.0, 1.5])
    moved = ("look", LineGizmo([[0, 0, 1.6], [1.0, -2.0, 1.5]], edit="target"))
    viewport.show_snapshot(fake_snapshot(seq=2, gizmos=(moved,)))
    assert np.allclose(viewport.gizmos.items["look"].mesh.points[-1], [1.0, -2.0, 1.5])


def test_box_gizmo_drags_and_follows_edits_made_elsewhere(viewport, qtbot, fake_snapshot):
    import pyvista as pv

    edits = []
    viewport.gizmoEdited.connect(lambda n, ch: edits.append((n, ch)))
    box = BoxGizmo([-1, -1, 0], [1, 1, 2], edit=("box_min", "box_max"))
    viewport.show_snapshot(fake_snapshot(gizmos=(("bounds", box),)))
    assert edits == []  # building the box widget is not an edit
    gizmo = viewport.gizmos.items["bounds"]
    with qtbot.waitSignal(viewport.gizmoEdited) as sig:  # the user drags a face of the box
        gizmo.widget.PlaceWidget((-1, 1.5, -1, 1, 0, 2))
        gizmo.widget.InvokeEvent("EndInteractionEvent")
    assert sig.args[0] == "bounds" and np.allclose(sig.args[1]["box_max"], [1.5, 1, 2])
    viewport.show_snapshot(fake_snapshot(seq=2, gizmos=(("bounds", BoxGizmo(box.lower, [2, 1, 2], edit=box.edit)),)))
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
    ghost = viewport.ghosts.items["ik"]
    assert ghost.visible and np.allclose(ghost.mesh.points, ik)
    colour = ghost.actors[0].GetProperty().GetColor()
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


def test_ghost_legend_names_each_ghost_in_its_colour(viewport, fake_snapshot):
    snap = fake_snapshot()
    ghosts = {"sparseposer": snap.positions + [1.0, 0, 0], "rpm": snap.positions - [1.0, 0, 0]}
    viewport.show_snapshot(fake_snapshot(seq=2, ghosts=ghosts))
    labels = viewport.ghosts.labels
    assert [labels[n].GetInput() for n in ghosts] == ["- sparseposer", "- rpm"]
    for name in ghosts:
        assert labels[name].GetVisibility()
        assert np.allclose(
            labels[name].GetTextProperty().GetColor(), viewport.ghosts.items[name].actors[0].GetProperty().GetColor()
        )
    assert labels["sparseposer"].GetPosition()[1] > labels["rpm"].GetPosition()[1]  # listed top down
    viewport.show_snapshot(fake_snapshot(seq=3, ghosts={"rpm": ghosts["rpm"]}))
    assert not labels["sparseposer"].GetVisibility() and labels["rpm"].GetVisibility()


def test_follow_camera_glides_with_the_hips_and_holds_still_when_off(viewport, fake_snapshot):
    now = [100.0]  # the glide's clock, stepped by hand: drawing time must not count
    viewport.clock = lambda: now[0]
    viewport._followed_at = now[0]
    snap = fake_snapshot()
    moved = snap.positions + [2.0, 0, 0]
    focus_x = viewport.plotter.camera.focal_point[0]
    now[0] += 0.005
    viewport.show_snapshot(fake_snapshot(seq=2, positions=moved, playing=True))  # ~no time passed: barely moves
    assert viewport.plotter.camera.focal_point[0] - focus_x < 0.5
    for seq in range(3, 6):
        now[0] += 0.5  # half a second per redraw
        viewport.show_snapshot(fake_snapshot(seq=seq, positions=moved, playing=True))
    cam = viewport.plotter.camera
    assert cam.focal_point[0] == pytest.approx(moved[0, 0], abs=0.01)
    offset = np.subtract(cam.position, cam.focal_point)
    viewport.follow = False
    now[0] += 1.0
    viewport.show_snapshot(fake_snapshot(seq=9, positions=moved + [3.0, 0, 0]))
    assert cam.focal_point[0] == pytest.approx(moved[0, 0], abs=0.01)
    assert np.allclose(np.subtract(cam.position, cam.focal_point), offset)  # the user's angle is kept


def test_a_paused_frame_is_followed_all_the_way_at_once(viewport, fake_snapshot):
    """Paused, no later redraw would finish a glide: a seek's frame is centred at once."""
    now = [100.0]
    viewport.clock = lambda: now[0]  # no time passes at all
    viewport._followed_at = now[0]
    moved = fake_snapshot().positions + [2.0, -1.5, 0]
    viewport.show_snapshot(fake_snapshot(seq=2, positions=moved, playing=False))
    cam = viewport.plotter.camera
    assert cam.focal_point[:2] == pytest.approx(tuple(moved[0, :2]), abs=1e-6)
    img = viewport.plotter.screenshot(return_img=True)
    orange = (img[..., 0] > 200) & (img[..., 1] > 80) & (img[..., 1] < 170) & (img[..., 2] < 80)
    cols = np.nonzero(orange.any(axis=0))[0]
    assert abs(0.5 * (cols.min() + cols.max()) - img.shape[1] / 2) < 0.1 * img.shape[1]  # centred


def test_a_frame_renders_once_queries_the_bounds_once_and_runs_no_python_filter(viewport, fake_snapshot):
    """What a drawn snapshot may cost: one render, one clipping-range (bounds) query, and
    no pyvista Python algorithm between a moving mesh and its mapper (those re-ran on
    every frame: smooth shading recomputed the target spheres' normals, the RGB arrays
    went through a Python filter, and pyvista's camera setter queried the bounds again)."""
    import vtk

    now = [100.0]
    viewport.clock = lambda: now[0]
    viewport._followed_at = now[0]
    renders, bounds = [], []
    viewport.plotter.render_window.AddObserver("EndEvent", lambda *_: renders.append(1))
    viewport.plotter.renderer.AddObserver("ResetCameraClippingRangeEvent", lambda *_: bounds.append(1))
    snap = fake_snapshot()
    viewport.show_snapshot(snap)
    renders.clear(), bounds.clear()
    now[0] += 0.1
    viewport.show_snapshot(fake_snapshot(seq=2, positions=snap.positions + [0.5, 0, 0]))  # the camera follows
    assert len(renders) == 1 and len(bounds) == 1
    props = viewport.plotter.renderer.GetViewProps()
    for i in range(props.GetNumberOfItems()):
        actor = props.GetItemAsObject(i)
        mapper = actor.GetMapper() if isinstance(actor, vtk.vtkActor) else None
        while mapper is not None and mapper.GetNumberOfInputPorts() and mapper.GetNumberOfInputConnections(0):
            mapper = mapper.GetInputConnection(0, 0).GetProducer()
            assert isinstance(mapper, vtk.vtkTrivialProducer), f"{type(mapper).__name__} feeds a drawable"


def blue_fraction(img: np.ndarray) -> float:
    """Share of pixels tinted by the ik ghost's blue (#4da3ff), blended or not."""
    r, g, b = (img[..., i].astype(int) for i in range(3))
    return float(np.mean((b > 150) & (b > r + 60) & (b > g + 10)))


def test_ghosts_are_thin_translucent_and_show_through_the_reconstruction(viewport, fake_snapshot):
    """A ghost on the same pose as the reconstruction would vanish inside its thicker,
    opaque figure, so it is a thin translucent overlay drawn over it."""
    snap = fake_snapshot(ground_truth=None)
    viewport.show_ground_truth = False
    viewport.show_snapshot(fake_snapshot(seq=2, ghosts={"ik": snap.positions.copy()}))
    bones = viewport.ghosts.items["ik"].actors[0].GetProperty()
    assert bones.GetOpacity() < 0.8
    assert bones.GetLineWidth() < viewport.reconstruction.bones.GetProperty().GetLineWidth()
    img = viewport.plotter.screenshot(return_img=True)
    assert blue_fraction(img) > 0.0005, "the ghost is hidden under the reconstruction"


def test_ghost_colour_comes_from_the_layer_colour_function(viewport, fake_snapshot):
    viewport.ghosts.color_of = lambda name, i: "#ff0000" if name == "mine" else "#00ff00"
    snap = fake_snapshot()
    viewport.show_snapshot(fake_snapshot(seq=2, ghosts={"mine": snap.positions + [1, 0, 0]}))
    assert np.allclose(viewport.ghosts.items["mine"].actors[0].GetProperty().GetColor(), (1, 0, 0))


def test_body_view_draws_shaded_capsules_updated_in_place(viewport, fake_snapshot):
    snap = fake_snapshot()
    viewport.set_display("body")
    viewport.show_snapshot(snap)
    body = viewport.body
    mesh = body.mesh
    assert body.visible and not viewport.reconstruction.visible
    # every capsule surrounds its bone: the mesh spans the skeleton plus the radii
    lo, hi = snap.positions.min(0), snap.positions.max(0)
    assert np.all(mesh.points.min(0) < lo) and np.all(mesh.points.max(0) > hi)
    assert np.all(mesh.points.min(0) > lo - 0.2)
    img = viewport.plotter.screenshot(return_img=True)
    assert orange_fraction(img) > 0.01  # a filled body covers far more pixels than sticks
    viewport.show_snapshot(fake_snapshot(seq=2, positions=snap.positions + [0.5, 0, 0]))
    assert viewport.body.mesh is mesh
    assert mesh.points[:, 0].min() == pytest.approx(body._points(snap.positions)[0][:, 0].min() + 0.5)
    # the shadow sits on the floor under the body
    shadow = body.shadow_mesh.points
    assert np.allclose(shadow[:, 2], shadow[0, 2]) and 0 < shadow[0, 2] < 0.01
    assert shadow[0, 0] == pytest.approx(snap.positions[:, 0].mean() + 0.5)
    viewport.set_display("stick")
    viewport.show_snapshot(fake_snapshot(seq=3))
    assert viewport.reconstruction.visible and not body.visible


def test_capsule_normals_point_out_of_their_bone(viewport):
    from engine import skeleton as sk

    pose = sk.Skeleton.canonical().rest_positions() + [0, 0, 1.0]
    pts, normals = viewport.body._points(pose)
    assert np.allclose(np.linalg.norm(normals, axis=1), 1.0)
    t = len(viewport.body._dirs)
    p, j = viewport.body.bones[7]
    a, b = pose[p], pose[j]
    seg = pts[7 * t : 8 * t]
    # distance from each vertex to the bone segment equals the capsule radius
    u = np.clip(((seg - a) @ (b - a)) / ((b - a) @ (b - a)), 0, 1)
    dist = np.linalg.norm(seg - (a + u[:, None] * (b - a)), axis=1)
    assert np.allclose(dist, viewport.body.radius[7], atol=1e-9)


@pytest.mark.parametrize("preset, axis, sign", [("front", 1, -1), ("side", 0, 1), ("top", 2, 1)])
def test_camera_presets_look_at_the_character_from_their_side(viewport, fake_snapshot, preset, axis, sign):
    viewport.set_camera(preset, np.array([1.0, 2.0, 0.9]))
    cam = viewport.plotter.camera
    offset = np.subtract(cam.position, cam.focal_point)
    assert np.allclose(cam.focal_point[:2], [1.0, 2.0])
    assert sign * offset[axis] > 0.9 * np.linalg.norm(offset)
    with pytest.raises(ValueError, match="known"):
        viewport.set_camera("bottom")


def test_a_bvh_dropped_on_the_3d_view_is_offered_to_the_window(viewport, qtbot, tmp_path):
    from PyQt6.QtCore import QMimeData, QPointF, Qt, QUrl
    from PyQt6.QtGui import QDragEnterEvent, QDropEvent
    from PyQt6.QtWidgets import QApplication

    path = tmp_path / "walk.bvh"
    path.write_text("HIERARCHY\n")
    mime = QMimeData()
    mime.setUrls([QUrl.fromLocalFile(str(path))])
    target = viewport.plotter  # the VTK widget fills the view: it is what a drop lands on
    enter = QDragEnterEvent(
        target.rect().center(), Qt.DropAction.CopyAction, mime, Qt.MouseButton.NoButton, Qt.KeyboardModifier.NoModifier
    )
    QApplication.sendEvent(target, enter)
    assert enter.isAccepted()
    drop = QDropEvent(
        QPointF(target.rect().center()),
        Qt.DropAction.CopyAction,
        mime,
        Qt.MouseButton.NoButton,
        Qt.KeyboardModifier.NoModifier,
    )
    with qtbot.waitSignal(viewport.filesDropped, timeout=1000) as sig:
        QApplication.sendEvent(target, drop)
    assert sig.args[0] == [str(path)]


def test_a_pin_shows_the_joint_it_holds_and_a_line_to_it(viewport, fake_snapshot):
    """Nothing showed which joint a pin held."""
    from engine.constraints.pin import PinConstraint

    snap = fake_snapshot()
    pin = PinConstraint(name="drag lelbow", joint="lelbow", position=np.array([0.5, -0.3, 1.4]))
    viewport.show_snapshot(fake_snapshot(gizmos=(("drag lelbow", pin.gizmo(snap.positions)),)))
    item = viewport.gizmos.items["drag lelbow"]
    assert item.label is not None and item.label.GetInput() == "lelbow"
    elbow = snap.positions[16]
    assert np.allclose(item.tether.points, [elbow, [0.5, -0.3, 1.4]])
    moved = snap.positions + [0.1, 0, 0]
    viewport.show_snapshot(fake_snapshot(seq=2, positions=moved, gizmos=(("drag lelbow", pin.gizmo(moved)),)))
    assert viewport.gizmos.items["drag lelbow"] is item  # moved in place
    assert np.allclose(item.tether.points[0], moved[16])


def test_the_view_lights_with_the_headlight_and_the_key_light_only(viewport):
    """Each lit pixel evaluates every light switched on: the kit's fill and back lights
    cost software GL ~7 % of a draw for little visible change."""
    lights = viewport.plotter.renderer.GetLights()
    on = [lights.GetItemAsObject(i) for i in range(lights.GetNumberOfItems()) if lights.GetItemAsObject(i).GetSwitch()]
    assert len(on) == 2 and sum(light.LightTypeIsHeadlight() for light in on) == 1
    assert max(light.GetIntensity() for light in on) >= 0.5  # the key light


def _wheel(widget, x: float, y: float, notches: float) -> None:
    """A mouse wheel turned ``notches`` at widget pixel ``(x, y)``, as Qt delivers it."""
    from PyQt6.QtCore import QPoint, QPointF, Qt
    from PyQt6.QtGui import QWheelEvent
    from PyQt6.QtWidgets import QApplication

    pos = QPointF(x, y)
    event = QWheelEvent(
        pos,
        QPointF(widget.mapToGlobal(pos)),
        QPoint(0, 0),
        QPoint(0, int(120 * notches)),
        Qt.MouseButton.NoButton,
        Qt.KeyboardModifier.NoModifier,
        Qt.ScrollPhase.NoScrollPhase,
        False,
    )
    QApplication.sendEvent(widget, event)


def test_the_wheel_zooms_toward_the_point_under_the_mouse(viewport, fake_snapshot):
    """As Blender's "zoom to mouse position": the point under the mouse stays under it,
    the distance shrinks by a notch's factor; turned back, the camera is where it was."""
    viewport.show_snapshot(fake_snapshot())
    ren, cam, widget = viewport.plotter.renderer, viewport.plotter.camera, viewport.plotter
    before = (np.array(cam.position), np.array(cam.focal_point))
    # a world point on the focal plane, right of and above the centre of the view
    forward = np.subtract(cam.focal_point, cam.position)
    up = np.array(cam.up) - forward * (np.dot(cam.up, forward) / np.dot(forward, forward))
    right = np.cross(forward, up)
    point = np.array(cam.focal_point) + 0.6 * right / np.linalg.norm(right) + 0.4 * up / np.linalg.norm(up)

    def display(p):
        ren.SetWorldPoint(*p, 1.0)
        ren.WorldToDisplay()
        return np.array(ren.GetDisplayPoint()[:2])

    x, y = display(point)
    ratio = widget.devicePixelRatioF()
    assert 40 < x < widget.width() * ratio - 40 and 40 < y < widget.height() * ratio - 40
    distance = cam.distance
    _wheel(widget, x / ratio, widget.height() - 1 - y / ratio, 1)
    assert cam.distance == pytest.approx(distance / 1.21, rel=1e-6)
    assert np.allclose(display(point), (x, y), atol=1.5)  # still under the mouse
    _wheel(widget, x / ratio, widget.height() - 1 - y / ratio, -1)
    assert np.allclose(cam.position, before[0], atol=1e-3) and np.allclose(cam.focal_point, before[1], atol=1e-3)


def green_fraction(img: np.ndarray) -> float:
    """Share of pixels with the ground truth's green."""
    r, g, b = (img[..., i].astype(int) for i in range(3))
    return float(np.mean((g > 120) & (g > r + 40) & (g > b + 40)))


def test_view_options_redraw_a_paused_frame_at_once(viewport, fake_snapshot):
    """Nothing else redraws a paused studio: hiding the ground truth, the ghosts or
    switching to the body must change the picture without another snapshot."""
    snap = fake_snapshot()
    viewport.show_snapshot(fake_snapshot(seq=2, ghosts={"ik": snap.positions + [0.6, 0, 0]}))
    before = viewport.plotter.screenshot(return_img=True)
    assert green_fraction(before) > 0.0005 and blue_fraction(before) > 0.0005
    viewport.show_ground_truth = False
    hidden = viewport.plotter.screenshot(return_img=True)
    assert green_fraction(hidden) < 0.2 * green_fraction(before)
    assert "ground truth" not in viewport._caption
    viewport.show_ghosts = False
    assert blue_fraction(viewport.plotter.screenshot(return_img=True)) < 0.2 * blue_fraction(before)
    sticks = orange_fraction(viewport.plotter.screenshot(return_img=True))
    viewport.set_display("body")
    assert viewport.body.visible and orange_fraction(viewport.plotter.screenshot(return_img=True)) > 2 * sticks
    viewport.show_ground_truth = True
    assert green_fraction(viewport.plotter.screenshot(return_img=True)) > 0.5 * green_fraction(before)


def _caption_height(viewport) -> int:
    """Pixel rows of the caption's glyphs (light grey on the dark sky, top left)."""
    img = np.asarray(viewport.plotter.screenshot(return_img=True)).astype(int)
    top = img[: img.shape[0] // 6, : img.shape[1] * 3 // 4]
    rows = np.where(((top > 150).all(axis=2)).any(axis=1))[0]
    return int(rows.max() - rows.min() + 1) if len(rows) else 0


def test_the_caption_keeps_one_font_size_whatever_it_says(viewport, fake_snapshot):
    """The caption keeps one size whatever it says: "ik (orange)   ground truth (green)"
    and the longer "ik (orange)   no ground truth (tracker input)" (VTK's corner text
    would shrink the longer line to fit)."""
    viewport.show_snapshot(fake_snapshot(method="ik"))
    short = _caption_height(viewport)
    viewport.show_snapshot(fake_snapshot(seq=2, method="sparseposer", ground_truth=np.full((22, 3), np.nan)))
    assert "no ground truth" in viewport._caption
    assert short > 8 and _caption_height(viewport) == short
