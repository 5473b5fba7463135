"""The pose and key window driven programmatically: targets, keys, undo/redo of every edit
kind, the unsaved-changes prompt, export equal to ``bake``, the File menu entry."""

from __future__ import annotations

import numpy as np
import pytest
from PyQt6.QtWidgets import QApplication, QMessageBox

from engine import skeleton as sk
from engine.cli.main import main as cli
from tests.app.gui_helpers import close_now

pytestmark = pytest.mark.gui
LW = sk.JOINT_INDEX["lwrist"]


@pytest.fixture
def window(pose_window):
    return pose_window


def state(w):
    return (
        {
            j: (t.position.round(9).tolist(), t.weight, t.enabled, t.rotation is not None)
            for j, t in w.mode.targets.items()
        },
        [(k.frame, sorted(k.targets)) for k in w.scene.keys],
        w.scene.animation.frames,
        w.scene.animation.fps,
        w.scene.animation.interpolation,
        w.keys.interpolation.currentText(),
        w.mode.pose.positions.round(9).tolist(),
    )


def key_the_wrist(w, *keys: tuple, length: int) -> np.ndarray:
    """Drag the left wrist by each ``(frame, offset)``'s offset from where it starts and key
    it there; set the length (frames); the wrist's start (3,)."""
    start = w.mode.pose.positions[LW].copy()
    for frame, offset in keys:
        w.drag_joint("lwrist", start + offset)
        w.add_key(frame)
    w.keys.length.setValue(length)
    return start


def test_dragging_a_joint_makes_a_target_the_pose_follows(window, monkeypatch):
    # each move solves before the next: on a loaded machine that takes longer than the
    # merge window, which this test is not about
    monkeypatch.setattr("engine.authoring.history.MERGE_S", 60.0)
    start = window.mode.pose.positions[LW].copy()
    for k in range(1, 11):
        window.drag_joint("lwrist", start + [0.0, -0.02 * k, 0.0])
    assert list(window.mode.targets) == ["lwrist"] and list(window.targets.rows) == ["lwrist"]
    assert np.linalg.norm(window.mode.pose.positions[LW] - (start + [0, -0.2, 0])) < 0.01
    assert window.viewport.sensors.joints == ("lwrist",)
    assert window.undo.count() == 1  # the drag's moves merged into one step


def test_a_plain_press_on_a_joint_grabs_it(window):
    d = window.viewport.joints
    window.viewport.plotter.render()
    x, y = d._to_display(window.mode.pose.positions[[LW]])[0]
    assert d.press_plain(x, y) and d.joint == LW  # no Ctrl needed in pose mode
    d.release()
    assert not d.press_plain(2, 2)  # off the body the camera turns


def test_alt_drag_turns_the_joint_by_the_angle_swept_about_it(window, monkeypatch):
    from PyQt6.QtCore import Qt

    import app.pose_window as pw
    from engine.kinematics import quat_np as QN
    from engine.kinematics.fk import fk

    monkeypatch.setattr(
        pw.QApplication, "queryKeyboardModifiers", staticmethod(lambda: Qt.KeyboardModifier.AltModifier)
    )
    w = window
    pose = w.mode.pose
    start = fk(pose.local_rot, pose.root_pos, w.mode.character.skeleton.offsets)[1][LW]
    pivot = pose.positions[LW].copy()
    for a in np.radians(np.arange(0, 91, 10)):
        w.drag_joint("lwrist", pivot + 0.1 * np.array([np.cos(a), 0.0, np.sin(a)]))
    t = w.mode.targets["lwrist"]
    assert t.rotation is not None and np.allclose(t.position, pivot)
    turn = QN.mul(t.rotation, QN.conjugate(start))
    assert np.degrees(2 * np.arccos(min(1.0, abs(turn[0])))) == pytest.approx(90.0, abs=1.0)
    p = w.mode.pose
    now = fk(p.local_rot, p.root_pos, w.mode.character.skeleton.offsets)[1][LW]
    assert abs(float(now @ t.rotation)) == pytest.approx(1.0, abs=1e-9)
    assert w.undo.count() == 1 and "+rotation" in w.targets.rows["lwrist"]["label"].text()


def test_a_slow_solve_does_not_split_an_alt_drag(window, monkeypatch):
    """The gesture ends at a pause of the mouse, not at a solve slower than the pause."""
    import time

    from PyQt6.QtCore import Qt

    import app.pose_window as pw
    from engine.authoring.turns import TURN_GESTURE_S

    monkeypatch.setattr(
        pw.QApplication, "queryKeyboardModifiers", staticmethod(lambda: Qt.KeyboardModifier.AltModifier)
    )
    w = window
    turn = w.session.turn_joint

    def slow_turn(*args, **kwargs):
        time.sleep(1.2 * TURN_GESTURE_S)
        return turn(*args, **kwargs)

    monkeypatch.setattr(w.session, "turn_joint", slow_turn)
    pivot = w.mode.pose.positions[LW].copy()
    gestures = []
    for a in np.radians(np.arange(0, 41, 10)):
        w.drag_joint("lwrist", pivot + 0.1 * np.array([np.cos(a), 0.0, np.sin(a)]))
        gestures.append(w.turns.gesture)
    assert all(g is gestures[0] for g in gestures)


def test_every_edit_kind_undoes_and_redoes(window, qtbot):
    w = window
    start = w.mode.pose.positions[LW].copy()
    edits = [
        lambda: w.drag_joint("lwrist", start + [0.0, -0.1, 0.1]),
        lambda: w.targets.rows["lwrist"]["weight"].setValue(5.0),
        lambda: w.targets.rows["lwrist"]["turn"].setChecked(True),
        lambda: w.targets.rows["lwrist"]["enabled"].setChecked(False),
        lambda: w.add_key(0),
        lambda: w.drag_joint("rwrist", w.mode.pose.positions[sk.JOINT_INDEX["rwrist"]] + [0, 0, 0.2]),
        lambda: w.add_key(20),
        lambda: w.move_key(20, 30),
        lambda: w.keys.length.setValue(45),
        lambda: w.keys.fps.setValue(24.0),
        lambda: w.keys.interpolation.setCurrentText("spherical"),
        lambda: w.clear_target("rwrist"),
        lambda: w.delete_key(0),
        lambda: w.clear_all(),
    ]
    # a key is moved from its frame: the window goes there first (no undo step: no edit is
    # dropped), so the move's undo shows the key where it was
    went = {7: 20}
    before, after = [], [state(w)]  # each edit's, for its undo and its redo
    for i, edit in enumerate(edits):
        qtbot.wait(700)  # beyond the merge window: each edit is its own step
        if i in went:
            w.go_to(went[i])
            assert w.frame == went[i]
        before.append(state(w))
        edit()
        after.append(state(w))
        assert after[-1] != before[-1], edit
    assert w.undo.count() == len(edits) and w.dirty
    for i in range(len(edits), 0, -1):
        w.undo.undo()
        assert state(w) == before[i - 1], i
    for i in range(1, len(edits) + 1):
        w.undo.redo()
        assert state(w) == after[i], i


def test_the_window_exports_what_bake_writes_from_its_saved_scene(window, tmp_path):
    w = window
    key_the_wrist(w, (0, [0.0, -0.15, 0.05]), (20, [0.1, -0.1, 0.35]), length=21)
    w.files.save(tmp_path / "s.json")
    assert not w.dirty
    w.files.export_bvh(tmp_path / "studio.bvh")
    assert w.statusBar().currentMessage() == f"BVH written to {tmp_path / 'studio.bvh'}"
    assert w.files.suggested(".mp4") == str(tmp_path / "s.mp4")  # named after the scene, where it was saved
    assert cli(["bake", str(tmp_path / "s.json"), "--out", str(tmp_path / "cli.bvh"), "--no-progress"]) == 0
    assert (tmp_path / "cli.bvh").read_bytes() == (tmp_path / "studio.bvh").read_bytes()
    w.files.export_video(tmp_path / "v.mp4", (128, 96))
    import imageio_ffmpeg

    frames = imageio_ffmpeg.read_frames(str(tmp_path / "v.mp4"))
    meta = next(frames)
    assert meta["size"] == (128, 96) and sum(1 for _ in frames) == 21


def test_preview_plays_the_bake_and_going_to_a_key_poses_it(window, qtbot):
    w = window
    start = w.mode.pose.positions[LW].copy()
    w.drag_joint("lwrist", start + [0.0, -0.1, 0.3])
    w.add_key(10)
    w.clear_all()
    w.go_to(10)
    assert list(w.mode.targets) == ["lwrist"]
    assert np.linalg.norm(w.mode.pose.positions[LW] - (start + [0, -0.1, 0.3])) < 1e-6
    w.keys.length.setValue(15)
    w.playback.toggle()
    qtbot.waitUntil(lambda: not w.playback.timer.isActive(), timeout=10000)
    assert w.playback.baked is not None and len(w.playback.baked.motion) == 15


def test_closing_with_unsaved_edits_asks_and_cancel_keeps_the_window(window, monkeypatch):
    window.add_key(0)
    asked = []
    monkeypatch.setattr(
        QMessageBox, "question", lambda *a, **k: asked.append(a[1]) or QMessageBox.StandardButton.Cancel
    )
    assert not window.close() and window.isVisible() and asked == ["Unsaved changes"]
    monkeypatch.setattr(QMessageBox, "question", lambda *a, **k: QMessageBox.StandardButton.Discard)
    assert window.close()


def test_the_studio_file_menu_opens_a_pose_window_on_the_clip_frame(studio):
    from app.authoring_actions import open_pose_window

    assert {"new_pose", "export_video"} <= set(studio.actions_by_name)
    pose = open_pose_window(studio, 1.7, from_clip=True)
    try:
        assert pose.isVisible() and pose.mode.character.height == pytest.approx(1.7)
        assert np.allclose(pose.mode.pose.root_pos[:2], studio.session.motion.root_pos[studio.session.frame, :2])
    finally:
        close_now(pose)


def test_the_screenshot_shows_the_window_with_the_character(window, tmp_path):
    from PyQt6.QtGui import QImage

    assert window.files.screenshot(tmp_path / "s.png")
    img = QImage(str(tmp_path / "s.png"))
    assert img.width() >= window.width() - 2 and img.height() >= window.height() - 2
    vp = window.viewport.mapTo(window, window.viewport.rect().center())
    colours = {
        img.pixelColor(x, y).name() for x in range(vp.x() - 60, vp.x() + 60, 3) for y in range(0, img.height(), 3)
    }
    assert any(int(c[1:3], 16) > 180 and int(c[5:7], 16) < 90 for c in colours)  # the orange figure is drawn


def test_dragging_the_hips_moves_the_whole_body_live_and_keys_carry_root_and_facing(window, qtbot):
    from PyQt6.QtCore import Qt
    from PyQt6.QtTest import QTest

    from engine.authoring.character import heading_deg
    from tests.app.gui_helpers import mouse_drag, pixel_of

    w = window
    w.add_key(0)
    w.viewport.set_camera("front", w.hips())
    w.viewport.plotter.render()
    before = w.mode.pose.positions.copy()
    seen = []
    w.viewport.jointDragged.connect(lambda j, p: seen.append(w.mode.pose.root_pos.copy()))
    x, y = pixel_of(w.viewport, before[0])
    mouse_drag(w.viewport, (x, y), (x + 120, y), steps=8)
    moved = w.mode.pose.positions - before
    assert moved[0, 0] > 0.2 and np.allclose(moved, moved[0], atol=1e-9) and abs(moved[0, 2]) < 1e-9
    assert len(seen) == 8 and np.all(np.diff([r[0] for r in seen]) > 0)  # the body follows every move
    assert w.mode.targets == {} and w.undo.undo_text() == "move body"
    w.facing.selectAll()
    QTest.keyClicks(w.facing, "90")
    QTest.keyClick(w.facing, Qt.Key.Key_Return)
    assert w.mode.heading == 90.0
    w.add_key(20)
    w.keys.length.setValue(21)
    motion = w.playback.baked_scene().motion
    assert np.allclose(motion.root_pos[20, :2], w.mode.pose.root_pos[:2], atol=1e-6)
    assert np.allclose(motion.root_pos[0, :2], before[0, :2], atol=1e-6)
    assert 0.3 < (motion.root_pos[10, 0] - before[0, 0]) / moved[0, 0] < 0.7  # the in-between travels
    turn = heading_deg(motion.local_rot[20, 0]) - heading_deg(motion.local_rot[0, 0])
    assert turn == pytest.approx(90.0, abs=1.0)
    for _ in range(3):  # the length, the key, the turn (typed 9, 90: one step)
        w.undo.undo()
    assert w.mode.heading == 0.0 and w.facing.value() == 0.0


def test_the_3d_view_keeps_its_place_while_targets_are_added(window, qtbot):
    """The Targets dock grew with its first rows and long names, shifting the view 20-90 px
    between drags so the next grab missed."""
    from tests.app.gui_helpers import mouse_drag, pixel_of

    w = window
    qtbot.wait(50)
    w.viewport.plotter.render()
    place = w.viewport.geometry()
    for joint in ("lclavicle", "rshoulder", "upperneck"):
        x, y = pixel_of(w.viewport, w.mode.pose.positions[sk.JOINT_INDEX[joint]])
        mouse_drag(w.viewport, (x, y), (x + 10, y + 10), steps=2)
        assert joint in w.mode.targets
        qtbot.wait(20)
        assert w.viewport.geometry() == place, joint
    w.targets.rows["lclavicle"]["turn"].setChecked(True)  # the longer "(+rotation)" label
    qtbot.wait(20)
    assert w.viewport.geometry() == place


def test_scrubbing_between_keys_shows_the_in_between_and_a_key_dragged_moves(window, qtbot):
    from PyQt6.QtCore import Qt
    from PyQt6.QtTest import QTest

    from engine.kinematics.fk import fk_positions
    from tests.widgets.test_authoring_widgets import drag_on

    w = window
    start = key_the_wrist(w, (0, [0.0, -0.1, 0.1]), (20, [0.1, -0.2, 0.5]), length=31)
    s = w.keys.strip
    drag_on(s, s.x_of(4), s.x_of(10), steps=3)  # scrub from frame 4 to 10
    motion = w.playback.baked.motion
    shown = fk_positions(motion.local_rot[10], motion.root_pos[10], motion.skeleton.offsets)
    assert w.frame == 10 and np.allclose(w.mode.pose.positions, shown)
    assert np.allclose(w.viewport.joints.positions, shown) and w.keys.label.text().endswith("(in-between)")
    assert 0.1 < np.linalg.norm(shown[LW] - start) < 0.5  # neither key's wrist: on its way
    assert list(w.mode.targets) == ["lwrist"]  # the targets interpolated there
    w.add_key(10)  # keying the in-between keeps the motion
    assert np.abs(w.playback.baked_scene().motion.positions()[10] - shown).max() < 0.02
    w.undo.undo()
    drag_on(s, s.x_of(20), s.x_of(26))  # the key at 20 dragged to 26
    assert [k.frame for k in w.scene.keys] == [0, 26] and w.undo.undo_text() == "move key 20 -> 26"
    w.activateWindow()
    w.windowHandle().requestActivate()
    qtbot.waitUntil(lambda: QApplication.activeWindow() is w)
    w.go_to(0)
    w.keys.loop.setChecked(True)
    w.keys.fps.setValue(120.0)
    seen = []
    w.keys.strip.update = lambda *a, f=w.keys.strip: seen.append(f.current)  # every frame shown
    QTest.keyClick(w.viewport, Qt.Key.Key_Space)
    assert w.playback.playing and w.keys.preview.text() == "Stop"
    qtbot.waitUntil(lambda: len(seen) > 40, timeout=10000)
    QTest.keyClick(w.viewport, Qt.Key.Key_Space)
    assert not w.playback.playing and 30 in seen and seen.index(0, 1) > seen.index(30)  # looped


def test_dragging_the_z_ring_turns_the_head_about_the_vertical_without_tilting_it(window, qtbot):
    from engine.kinematics import quat_np as QN
    from tests.app.gui_helpers import mouse_drag, pixel_of
    from widgets.viewport.rings import AXES, circle

    w = window
    head = sk.JOINT_INDEX["upperneck"]
    w.viewport.set_camera("top", w.hips())
    w.viewport.plotter.render()
    x, y = pixel_of(w.viewport, w.mode.pose.positions[head])
    mouse_drag(w.viewport, (x, y), (x, y), steps=1)  # a click on the head selects it: its rings show
    rings = w.viewport.rings
    assert w.selected == "upperneck" and rings.visible and rings.shown == (0, 1, 2)
    before = w.turns.world_rotation("upperneck")
    facing = np.asarray(rings._arrow_mesh.points).mean(0) - w.mode.pose.positions[head]  # on the cone's axis
    ring = circle(rings.center, AXES[2], rings.radius, 72)  # 5 degrees apart, counter-clockwise from above
    w.viewport.plotter.render()
    path = [pixel_of(w.viewport, ring[k]) for k in (0, 4, 8)]  # 0 -> 40 degrees, from where an edge-on ring crosses
    mouse_drag(w.viewport, path[0], path[2], steps=8)
    t = w.mode.targets["upperneck"]
    turn = QN.mul(t.rotation, QN.conjugate(before))
    assert np.degrees(2 * np.arccos(min(1.0, abs(turn[0])))) == pytest.approx(40.0, abs=2.0)
    assert abs(turn[3]) > 0.99 * np.linalg.norm(turn[1:])  # about the vertical only
    now = w.turns.world_rotation("upperneck")
    assert abs(float(now @ t.rotation)) == pytest.approx(1.0, abs=1e-9)
    up = lambda q: QN.rotate(q, np.array([0.0, 0.0, 1.0]))  # noqa: E731
    assert up(now)[2] == pytest.approx(up(before)[2], abs=1e-6)  # no tilt: the head leans from vertical as before
    turned = np.asarray(rings._arrow_mesh.points).mean(0) - w.mode.pose.positions[head]
    yaw = np.degrees(np.arctan2(turned[1], turned[0]) - np.arctan2(facing[1], facing[0]))
    assert (yaw + 180) % 360 - 180 == pytest.approx(40.0, abs=3.0)  # the facing arrow turned with it
    assert w.undo.undo_text() == "turn upperneck"
    w.actions_by_name["deselect"].trigger()
    assert not rings.visible and w.selected is None


def test_the_hips_ring_turns_the_whole_body(window):
    w = window
    w.drag_joint("root", w.mode.pose.root_pos)
    assert w.viewport.rings.shown == (2,)  # only the turn about the vertical
    w.turns.by_ring(2, 0.0, True)
    w.turns.by_ring(2, np.radians(30.0), False)
    assert w.mode.heading == pytest.approx(30.0) and w.facing.value() == pytest.approx(30.0)


def test_a_saved_scene_opens_again_in_a_pose_window(window, tmp_path, vae, monkeypatch):
    """The pose window could save a scene but not open one."""
    from engine.authoring.document import load_authoring
    from engine.authoring.pose_mode import PoseMode
    from engine.authoring.session import AuthoringSession

    w = window
    key_the_wrist(w, (0, [0.0, -0.15, 0.05]), (20, [0.1, -0.1, 0.35]), length=25)
    w.move_body(np.array([0.3, 0.0, 0.0]))
    w.add_key(20)
    w.constraints.add("floor")
    w.files.save(tmp_path / "s.json")
    w.files.export_bvh(tmp_path / "first.bvh")
    from app.pose_window import PoseWindow
    from tests.app.gui_helpers import close_now

    other = PoseWindow(AuthoringSession(PoseMode(vae, 1.6)))  # another height: the scene's wins
    other.show()
    try:
        other.drag_joint("lwrist", other.mode.pose.positions[LW] + [0, 0, 0.1])  # an unsaved edit
        asked = []
        monkeypatch.setattr(
            QMessageBox, "question", lambda *a, **k: asked.append(a[1]) or QMessageBox.StandardButton.Discard
        )
        from PyQt6.QtWidgets import QFileDialog

        monkeypatch.setattr(
            QFileDialog, "getOpenFileName", staticmethod(lambda *a, **k: (str(tmp_path / "s.json"), ""))
        )
        other.actions_by_name["open"].trigger()
        assert asked == ["Unsaved changes"]
        assert other.mode.character.height == pytest.approx(1.75)
        assert [k.frame for k in other.scene.keys] == [0, 20] and other.scene.animation.frames == 25
        assert [c.name for c in other.mode.constraints] == [
            c.name for c in load_authoring(tmp_path / "s.json").constraints
        ]
        assert other.mode.constraints is other.scene.constraints
        assert other.frame == 0 and other.undo.count() == 0 and not other.dirty
        assert "Opened s.json: 2 keys, 1 constraint(s)" in other.statusBar().currentMessage()
        other.files.export_bvh(tmp_path / "again.bvh")
        assert (tmp_path / "again.bvh").read_bytes() == (tmp_path / "first.bvh").read_bytes()
        (tmp_path / "bad.json").write_text('{"format": "dragposer-scene", "version": 2, "animation": {"fps": "fast"}}')
        shown = []
        monkeypatch.setattr(QMessageBox, "warning", lambda *a, **k: shown.append(a[2]))
        monkeypatch.setattr(
            QFileDialog, "getOpenFileName", staticmethod(lambda *a, **k: (str(tmp_path / "bad.json"), ""))
        )
        other.actions_by_name["open"].trigger()
        assert len(shown) == 1 and shown[0].count("bad.json") == 1 and "fps" in shown[0]
        assert [k.frame for k in other.scene.keys] == [0, 20]  # a bad file changes nothing
    finally:
        close_now(other)


def test_the_bake_runs_on_a_worker_with_a_dialog_whose_cancel_changes_nothing(window, qtbot, monkeypatch):
    """Scrubbing between keys bakes off the GUI thread (the event loop runs, the progress
    dialog shows); Cancel stops it, the frame, the keys and the history stay as they were."""
    import threading

    from PyQt6.QtCore import QTimer
    from PyQt6.QtWidgets import QPushButton

    w = window
    key_the_wrist(w, (0, [0.0, -0.1, 0.1]), (150, [0.1, -0.2, 0.5]), length=151)
    steps, state_before = w.undo.count(), state(w)
    shown = []
    monkeypatch.setattr(QMessageBox, "warning", lambda *a, **k: shown.append(a[2]))
    seen: dict = {}

    def watch() -> None:
        r = w.jobs
        # the dialog takes the worker's count at its next poll (POLL_MS), so wait for the
        # dialog's own value rather than the worker's count alone
        if r.running and r.dialog is not None and r.dialog.isVisible() and r.dialog.value() >= 5:
            seen["worker"] = r.thread is not threading.main_thread() and r.thread.is_alive()
            seen["progress"] = (r.done, r.dialog.maximum())
            r.dialog.findChild(QPushButton).click()  # Cancel

    timer = QTimer(interval=10)
    timer.timeout.connect(watch)
    timer.start()
    w.go_to(75)  # between the keys: it needs the bake
    timer.stop()
    # the timer's callback saw the worker running and clicked Cancel: the loop ran during the bake
    assert seen.get("worker") and seen["progress"][1] == 153  # 2 keys + 151 frames
    assert shown == ["the bake did not finish: cancelled"]
    assert w.frame == 0 and w.playback.baked is None and w.undo.count() == steps and state(w) == state_before
    assert not w.jobs.running and w.jobs.dialog is None


def test_the_targets_and_rings_hide_while_the_bake_plays_and_come_back_on_stop(window, qtbot):
    """The target spheres and the selected joint's rings belong to the pose being edited:
    they stayed where the key put them while the played wrist waved elsewhere."""
    w = window
    key_the_wrist(w, (0, [0.0, -0.1, 0.1]), (20, [0.1, -0.2, 0.5]), length=31)
    w.go_to(0)
    w.selected = "lwrist"
    w.turns.show_handles()
    vp = w.viewport
    assert vp.sensors._actor.GetVisibility() and vp.rings.visible
    w.playback.toggle()
    assert w.playback.playing
    qtbot.waitUntil(lambda: w.playback.frame >= 5, timeout=10000)
    assert not vp.sensors._actor.GetVisibility() and not vp.sensors._axes_actor.GetVisibility()
    assert not vp.rings.visible and not vp.rings.arrow.GetVisibility()
    w.playback.toggle()
    assert not w.playback.playing
    assert vp.sensors._actor.GetVisibility() and vp.rings.visible
    assert np.allclose(vp.sensors.positions[0], w.mode.targets["lwrist"].position)
