"""Motion paths in both windows, driven by real mouse and key events: the selected
joint's path over the keyed range (pose window) or the clip (studio), the keys marked,
the current frame's dot, recomputed when a key changes or a range is re-solved, and
View ▸ Motion paths (P) / feet (Shift+P) remembered in the settings."""

from __future__ import annotations

import numpy as np
import pytest
from PyQt6.QtCore import QSettings, Qt
from PyQt6.QtTest import QTest
from PyQt6.QtWidgets import QApplication

from app.motion_path_view import FEET_KEY, SELECTED_COLOUR, SHOW_KEY
from engine import skeleton as sk
from engine.kinematics.fk import fk_positions
from tests.app.gui_helpers import close_now, mouse_drag, pixel_of
from tests.app.test_pose_selection import click
from widgets import style

pytestmark = pytest.mark.gui
LW, LE = sk.JOINT_INDEX["lwrist"], sk.JOINT_INDEX["lelbow"]


def colour_pixels(view, colour: str) -> int:
    img = view.grab_image()
    ptr = img.constBits()
    ptr.setsize(img.sizeInBytes())
    a = np.frombuffer(ptr, np.uint8).reshape(img.height(), img.bytesPerLine())[:, : 3 * img.width()]
    rgb = a.reshape(img.height(), img.width(), 3).astype(int)
    return int((np.abs(rgb - style.hex_to_rgb(colour)).sum(axis=2) < 30).sum())


@pytest.fixture
def window(qtbot, vae, tmp_path, monkeypatch):
    from PyQt6.QtWidgets import QMessageBox

    from app.pose_window import PoseWindow
    from engine.authoring.pose_mode import PoseMode
    from engine.authoring.session import AuthoringSession

    monkeypatch.setattr(QMessageBox, "question", lambda *a, **k: QMessageBox.StandardButton.Discard)
    settings = QSettings(str(tmp_path / "studio.ini"), QSettings.Format.IniFormat)
    w = PoseWindow(AuthoringSession(PoseMode(vae, 1.75)), settings=settings)
    w.resize(1000, 700)
    w.show()
    qtbot.waitExposed(w)
    w.activateWindow()  # the window's shortcuts (K, P) need it active
    w.windowHandle().requestActivate()
    qtbot.waitUntil(lambda: QApplication.activeWindow() is w)
    yield w
    close_now(w)


def drag_wrist(w, by: tuple[float, float]) -> None:
    view = w.viewport
    view.plotter.render()
    x, y = pixel_of(view, w.mode.pose.positions[LW])
    mouse_drag(view, (x, y), (x + by[0], y + by[1]), steps=6)


def test_the_pose_windows_path_follows_the_keys_and_the_pose(window, qtbot):
    w = window
    view, layer = w.viewport, w.viewport.paths
    drag_wrist(w, (-20, 30))
    QTest.keyClick(view, Qt.Key.Key_K)  # a key at frame 0
    w.keys.frameChanged.emit(20)  # the key strip's playhead to 20
    drag_wrist(w, (-60, 60))
    QTest.keyClick(view, Qt.Key.Key_K)
    assert [k.frame for k in w.scene.keys] == [0, 20]
    qtbot.waitUntil(lambda: layer.shown and layer.lines.n_points == 21, timeout=5000)
    assert w.paths.joints == ("lwrist",) and not w.paths.paths.exact  # before the bake: the preview
    line = layer.paths["lwrist"]
    np.testing.assert_allclose(layer.marks.points, line[[0, 20]], atol=1e-9)
    np.testing.assert_allclose(line[20], w.mode.pose.positions[LW], atol=0.005)
    np.testing.assert_allclose(layer.current.points, w.mode.pose.positions[[LW]], atol=1e-9)
    view.plotter.render()
    assert colour_pixels(view, SELECTED_COLOUR) > 40, "the path is on screen"
    # posing moves the current frame's dot at once; the path waits for a key
    drag_wrist(w, (40, 0))
    np.testing.assert_allclose(layer.current.points, w.mode.pose.positions[[LW]], atol=1e-9)
    np.testing.assert_allclose(layer.paths["lwrist"], line)
    w.keys.frameChanged.emit(10)  # scrubbing between keys bakes them: the path is the bake's
    qtbot.waitUntil(lambda: w.paths.paths is not None and w.paths.paths.exact, timeout=30000)
    m = w.session.baked.motion
    baked = fk_positions(m.local_rot[:21], m.root_pos[:21], m.skeleton.offsets)[:, LW]
    np.testing.assert_allclose(layer.paths["lwrist"], baked, atol=1e-9)
    np.testing.assert_allclose(layer.current.points, baked[[10]], atol=1e-6)
    drag_wrist(w, (0, 50))
    QTest.keyClick(view, Qt.Key.Key_K)  # a third key: the path passes through it
    qtbot.waitUntil(lambda: layer.marks.n_points == 3, timeout=5000)
    np.testing.assert_allclose(layer.paths["lwrist"][10], w.mode.pose.positions[LW], atol=0.005)


def test_the_toggles_hide_the_path_show_the_feet_and_are_remembered(window, qtbot, vae):
    w = window
    view, layer = w.viewport, w.viewport.paths
    drag_wrist(w, (-20, 30))
    QTest.keyClick(view, Qt.Key.Key_K)
    w.keys.frameChanged.emit(15)
    drag_wrist(w, (-40, 40))
    QTest.keyClick(view, Qt.Key.Key_K)
    qtbot.waitUntil(lambda: layer.shown, timeout=5000)
    QTest.keyClick(view, Qt.Key.Key_P)
    assert not layer.shown and w.settings.value(SHOW_KEY, type=bool) is False
    QTest.keyClick(view, Qt.Key.Key_P)
    QTest.keyClick(view, Qt.Key.Key_P, Qt.KeyboardModifier.ShiftModifier)
    assert w.paths.joints == ("lwrist", "lankle", "rankle") and set(layer.paths) == {"lwrist", "lankle", "rankle"}
    assert layer.lines.n_points == 3 * 16 and layer.current.n_points == 3
    assert w.settings.value(FEET_KEY, type=bool) is True
    QTest.keyClick(view, Qt.Key.Key_Escape)  # deselected: the feet's paths alone
    assert set(layer.paths) == {"lankle", "rankle"}
    w.settings.setValue(SHOW_KEY, False)
    from app.pose_window import PoseWindow
    from engine.authoring.pose_mode import PoseMode
    from engine.authoring.session import AuthoringSession

    other = PoseWindow(AuthoringSession(PoseMode(vae, 1.75)), settings=w.settings)
    try:
        assert not other.actions_by_name["motion_paths"].isChecked()
        assert other.actions_by_name["feet_paths"].isChecked()
    finally:
        close_now(other)


def test_the_studio_draws_the_clicked_joints_path_over_the_clip_and_after_a_resolve(studio, qtbot):
    from app.range_actions import resolve_range

    s, view, layer = studio.session, studio.viewport, studio.viewport.paths
    s.pause()
    qtbot.waitUntil(lambda: not s.latest.playing, timeout=10000)
    view.show_snapshot(s.latest)
    assert not layer.shown
    click(view, *pixel_of(view, s.latest.positions[LE]))  # a click: the camera does not turn
    assert studio.motion_paths.selected == "lelbow" and layer.shown
    clip = s.motion.positions()[:, LE]
    np.testing.assert_allclose(layer.current.points, clip[[s.frame]], atol=1e-9)  # paused: the dot at once
    np.testing.assert_allclose(layer.paths["lelbow"], clip, atol=1e-9)
    assert layer.marks.n_points == 2  # a dot each second: frames 0 and 60 of 120
    s.seek(30)
    qtbot.waitUntil(lambda: s.latest.frame == 30, timeout=10000)
    view.show_snapshot(s.latest)
    np.testing.assert_allclose(layer.current.points, clip[[30]], atol=1e-9)
    resolve_range(studio, 40, 70, blend=4).wait()
    qtbot.waitUntil(lambda: not np.allclose(layer.paths["lelbow"], clip), timeout=10000)
    np.testing.assert_allclose(layer.paths["lelbow"], s.motion.positions()[:, LE], atol=1e-9)
    np.testing.assert_allclose(layer.paths["lelbow"][:30], clip[:30], atol=1e-6)  # outside the range: as it was
