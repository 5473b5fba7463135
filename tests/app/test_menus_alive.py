"""Every action of every menu of the studio and of the pose window is alive: it is in its
menu, its Python wrapper is not deleted, it is connected, and triggering it (with every
file and option dialog answered "cancel") raises nothing. Both windows have Undo and
Redo first in their Edit menu, named after the edit, and Ctrl+Z / Ctrl+Shift+Z work."""

from __future__ import annotations

import numpy as np
import pytest
from PyQt6 import sip
from PyQt6.QtCore import Qt
from PyQt6.QtTest import QTest
from PyQt6.QtWidgets import QApplication, QDialog, QFileDialog, QInputDialog, QMenu, QMessageBox

from engine import skeleton as sk
from tests.app.gui_helpers import mouse_drag, pixel_of

pytestmark = pytest.mark.gui

#: Entries that end the window or wait for a person (tested by their own tests).
LEAVES_THE_WINDOW = ("Quit", "Close")


def menu_actions(window) -> list[tuple[str, object]]:
    """``(menu path, action)`` of every entry of ``window``'s menus, submenus included."""
    out = []

    def walk(menu: QMenu, path: str) -> None:
        for act in menu.actions():
            if act.isSeparator():
                continue
            name = f"{path} > {act.text().replace('&', '')}"
            if act.menu() is not None:
                walk(act.menu(), name)
            else:
                out.append((name, act))

    for top in window.menuBar().actions():
        walk(top.menu(), top.text().replace("&", ""))
    return out


@pytest.fixture
def no_dialogs(monkeypatch):
    """Every file, option, input and message dialog answers cancel (a message box is an
    entry's answer to a window with nothing to act on, e.g. saving a clip not opened from
    a file)."""
    for name in ("critical", "warning", "information", "question"):
        monkeypatch.setattr(QMessageBox, name, staticmethod(lambda *a, **k: QMessageBox.StandardButton.Cancel))
    for name in ("getOpenFileName", "getSaveFileName"):
        monkeypatch.setattr(QFileDialog, name, staticmethod(lambda *a, **k: ("", "")))
    monkeypatch.setattr(QFileDialog, "getOpenFileNames", staticmethod(lambda *a, **k: ([], "")))
    monkeypatch.setattr(QFileDialog, "getExistingDirectory", staticmethod(lambda *a, **k: ""))
    monkeypatch.setattr(QDialog, "exec", lambda self: QDialog.DialogCode.Rejected)
    for name in ("getText", "getInt", "getDouble", "getItem"):
        monkeypatch.setattr(QInputDialog, name, staticmethod(lambda *a, **k: (None, False)))


def trigger_all(window) -> list[str]:
    """Trigger every entry but those that close the window; the paths triggered."""
    done = []
    for name, act in menu_actions(window):
        assert not sip.isdeleted(act), name
        assert act.text(), name
        if name.split(" > ")[-1].rstrip(".") in LEAVES_THE_WINDOW:
            continue
        if act.isEnabled():
            act.trigger()
            QApplication.processEvents()
            done.append(name)
    for dialog in QApplication.topLevelWidgets():  # the help dialog is modeless
        if isinstance(dialog, QDialog) and dialog.isVisible():
            dialog.close()
    return done


def check_edit_menu(window) -> None:
    edit = next(a.menu() for a in window.menuBar().actions() if a.text().replace("&", "") == "Edit")
    first = [a for a in edit.actions() if not a.isSeparator()][:2]
    assert [a.text().split()[0].replace("&", "") for a in first] == ["Undo", "Redo"], [a.text() for a in first]
    assert first[0].shortcut().toString() == "Ctrl+Z"


def test_every_action_of_the_studio_menus_is_alive(studio, no_dialogs, qtbot):
    paths = [n for n, _ in menu_actions(studio)]
    assert len(paths) > 20 and any(p.startswith("View > Camera") for p in paths)
    for name, act in menu_actions(studio):
        assert act.receivers(act.triggered) + act.receivers(act.toggled) > 0, name
    check_edit_menu(studio)
    done = trigger_all(studio)
    assert any(p.startswith("File > Open motion") for p in done)


def test_every_action_of_the_pose_window_menus_is_alive(pose_window, no_dialogs, qtbot):
    w = pose_window
    paths = [n for n, _ in menu_actions(w)]
    for expected in (
        "Edit > Settle pose",
        "View > Camera > Front",
        "View > Camera > Top",
        "View > Draw character as > Shaded body",
        "Help > Keyboard and mouse...",
    ):
        assert expected in paths
    for name, act in menu_actions(w):
        if not name.startswith("Edit > Undo") and not name.startswith("Edit > Redo"):
            assert act.receivers(act.triggered) + act.receivers(act.toggled) > 0, name
    check_edit_menu(w)
    w.drag_joint("lwrist", w.mode.pose.positions[sk.JOINT_INDEX["lwrist"]] + [0.0, -0.1, 0.1])
    trigger_all(w)


def _activate(window, qtbot) -> None:
    window.activateWindow()
    window.windowHandle().requestActivate()  # window shortcuts need the active window
    qtbot.waitUntil(lambda: QApplication.activeWindow() is window)


def test_a_mouse_drag_in_the_pose_window_is_undone_by_ctrl_z_and_named_in_the_menu(pose_window, qtbot, monkeypatch):
    monkeypatch.setattr("engine.authoring.history.MERGE_S", 60.0)  # moves slowed by a loaded machine still merge
    w = pose_window
    _activate(w, qtbot)
    w.viewport.plotter.render()
    wrist = sk.JOINT_INDEX["lwrist"]
    before = w.mode.pose.positions.copy()
    x, y = pixel_of(w.viewport, before[wrist])
    mouse_drag(w.viewport, (x, y), (x + 40, y + 50))
    assert list(w.mode.targets) == ["lwrist"]
    moved = w.mode.pose.positions.copy()
    assert np.linalg.norm(moved[wrist] - before[wrist]) > 0.05
    assert w.actions_by_name["undo"].text() == "&Undo move target lwrist"
    QTest.keyClick(w.viewport, Qt.Key.Key_Z, Qt.KeyboardModifier.ControlModifier)
    assert w.mode.targets == {} and np.allclose(w.mode.pose.positions, before)
    assert w.actions_by_name["redo"].text() == "&Redo move target lwrist"
    QTest.keyClick(w.viewport, Qt.Key.Key_Z, Qt.KeyboardModifier.ControlModifier | Qt.KeyboardModifier.ShiftModifier)
    assert list(w.mode.targets) == ["lwrist"] and np.allclose(w.mode.pose.positions, moved)


def test_clear_all_puts_the_starting_pose_back(pose_window):
    w = pose_window
    start = w.mode.pose.positions.copy()
    for k in range(1, 8):
        w.drag_joint("lwrist", start[sk.JOINT_INDEX["lwrist"]] + [0.0, -0.04 * k, -0.08 * k])
    assert np.abs(w.mode.pose.positions - start).max() > 0.1
    folded = w.mode.pose.positions.copy()
    w.actions_by_name["clear_all"].trigger()
    assert w.mode.targets == {} and np.allclose(w.mode.pose.positions, start, atol=1e-6)
    w.undo.undo()
    assert np.allclose(w.mode.pose.positions, folded) and "lwrist" in w.mode.targets


#: Keys VTK's interactor style or pyvista bind by default: stereo, wireframe, surface,
#: camera reset, fly-to, joystick, picking modes, isometric view, zoom, point size, quit.
VTK_KEYS = (
    Qt.Key.Key_3,
    Qt.Key.Key_W,
    Qt.Key.Key_S,
    Qt.Key.Key_R,
    Qt.Key.Key_F,
    Qt.Key.Key_J,
    Qt.Key.Key_P,
    Qt.Key.Key_B,
    Qt.Key.Key_C,
    Qt.Key.Key_V,
    Qt.Key.Key_Up,
    Qt.Key.Key_Plus,
    Qt.Key.Key_U,
    Qt.Key.Key_E,
    Qt.Key.Key_Q,
)


def representations(plotter) -> list[int]:
    actors = plotter.renderer.GetActors()
    actors.InitTraversal()
    return [actors.GetNextActor().GetProperty().GetRepresentation() for _ in range(actors.GetNumberOfItems())]


def check_vtk_keys_do_nothing(view) -> None:
    """Keys sent straight to the VTK widget (no window shortcut takes them: the window is
    not active) change nothing and close nothing."""
    p = view.plotter
    p.render()
    styles = representations(p)
    camera = (tuple(p.camera.position), tuple(p.camera.focal_point), p.camera.view_angle)
    for key in VTK_KEYS:
        mods = Qt.KeyboardModifier.ShiftModifier if key == Qt.Key.Key_C else Qt.KeyboardModifier.NoModifier
        QTest.keyClick(p, key, mods)
        QApplication.processEvents()
    assert not p._closed
    assert not p.ren_win.GetStereoRender()
    assert representations(p) == styles  # w/s switch every actor to wireframe/surface
    assert (tuple(p.camera.position), tuple(p.camera.focal_point), p.camera.view_angle) == camera


def test_vtk_default_keys_do_nothing_in_the_studio_view(studio):
    check_vtk_keys_do_nothing(studio.viewport)


def test_vtk_default_keys_do_nothing_in_the_pose_view(pose_window):
    check_vtk_keys_do_nothing(pose_window.viewport)


def test_pose_window_camera_keys_and_display(pose_window, qtbot):
    w = pose_window
    _activate(w, qtbot)
    cam = w.viewport.plotter.camera
    QTest.keyClick(w.viewport, Qt.Key.Key_7)
    offset = np.subtract(cam.position, cam.focal_point)
    assert w.viewport.camera_preset == "top" and offset[2] > 0.9 * np.linalg.norm(offset)
    QTest.keyClick(w.viewport, Qt.Key.Key_1)
    offset = np.subtract(cam.position, cam.focal_point)
    assert w.viewport.camera_preset == "front" and offset[1] < -0.9 * np.linalg.norm(offset)
    QTest.keyClick(w.viewport, Qt.Key.Key_3)
    assert w.viewport.camera_preset == "side" and not w.viewport.plotter.ren_win.GetStereoRender()
    QTest.keyClick(w.viewport, Qt.Key.Key_Home)
    assert w.viewport.camera_preset == "home"
    w.move_body(np.array([1.5, -0.5, 0.0]))  # the character walks off the centre
    QTest.keyClick(w.viewport, Qt.Key.Key_F)
    assert np.allclose(cam.focal_point, w.hips()) and w.viewport.camera_preset == "home"
    QTest.keyClick(w.viewport, Qt.Key.Key_B)
    assert w.viewport.display == "body" and w.viewport.body.visible and not w.viewport.reconstruction.visible
    QTest.keyClick(w.viewport, Qt.Key.Key_S)
    assert w.viewport.display == "stick" and w.viewport.reconstruction.visible
