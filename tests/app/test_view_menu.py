"""View and Help menus: display mode, camera presets, the help dialog, drops on the 3D view."""

from __future__ import annotations

import numpy as np
import pytest
from PyQt6.QtCore import QMimeData, QPointF, Qt, QUrl
from PyQt6.QtGui import QDragEnterEvent, QDropEvent
from PyQt6.QtWidgets import QApplication

pytestmark = pytest.mark.gui


def _activate(studio, qtbot) -> None:
    studio.windowHandle().requestActivate()  # window shortcuts need the active window
    qtbot.waitUntil(lambda: QApplication.activeWindow() is studio)


def test_a_bvh_dropped_on_the_3d_view_opens(studio, qtbot, tmp_path, synthetic_motion):
    """The 3D view is the largest drop target, and pyvistaqt's interactor would take the drop
    as a mesh to read: the viewport hands it to the window instead."""
    from engine.motion.bvh import save_motion_bvh

    clip = tmp_path / "on-the-view.bvh"
    save_motion_bvh(clip, synthetic_motion.slice(0, 30))
    mime = QMimeData()
    mime.setUrls([QUrl.fromLocalFile(str(clip))])
    target = studio.viewport.plotter
    pos = target.rect().center()
    buttons, mods = Qt.MouseButton.NoButton, Qt.KeyboardModifier.NoModifier
    enter = QDragEnterEvent(pos, Qt.DropAction.CopyAction, mime, buttons, mods)
    QApplication.sendEvent(target, enter)
    assert enter.isAccepted()
    QApplication.sendEvent(target, QDropEvent(QPointF(pos), Qt.DropAction.CopyAction, mime, buttons, mods))
    assert studio.session.num_frames == 30 and "on-the-view.bvh" in studio.windowTitle()


def test_camera_presets_and_display_mode_from_the_keyboard(studio, qtbot):
    from PyQt6.QtTest import QTest

    _activate(studio, qtbot)
    cam = studio.viewport.plotter.camera
    QTest.keyClick(studio.viewport, Qt.Key.Key_7)  # top
    offset = np.subtract(cam.position, cam.focal_point)
    assert studio.viewport.camera_preset == "top" and offset[2] > 0.9 * np.linalg.norm(offset)
    QTest.keyClick(studio.viewport, Qt.Key.Key_1)  # front: the character faces -Y
    offset = np.subtract(cam.position, cam.focal_point)
    assert offset[1] < -0.9 * np.linalg.norm(offset)
    QTest.keyClick(studio.viewport, Qt.Key.Key_F)
    assert not studio.viewport.follow and not studio.actions_by_name["follow"].isChecked()
    QTest.keyClick(studio.viewport, Qt.Key.Key_B)
    assert studio.viewport.display == "body"
    seq = studio.session.latest.seq
    studio.session.seek(5)
    qtbot.waitUntil(lambda: studio.drawing._drawn_seq > seq)
    assert studio.viewport.body.visible and not studio.viewport.reconstruction.visible
    QTest.keyClick(studio.viewport, Qt.Key.Key_S)
    assert studio.viewport.display == "stick"


def test_help_lists_every_shortcut_of_the_menus(studio, qtbot):
    from app.menu_parts import show_help

    dialog = show_help(studio)
    try:
        rows = dict(dialog.rows())
        for keys in ("Space", "Home", "1", "3", "7", "F", "B", "Ctrl+O"):
            assert keys in rows, f"{keys} missing from the help"
        assert "Camera" in rows["7"] and "Top" in rows["7"]
        assert any("Ctrl + drag" in k for k in rows)
        assert show_help(studio) is dialog  # a second F1 raises it, no second window
    finally:
        dialog.close()
    from PyQt6.QtCore import QEvent
    from PyQt6.QtWidgets import QApplication

    QApplication.sendPostedEvents(None, QEvent.Type.DeferredDelete.value)
    again = show_help(studio)  # closed (and deleted): a new one
    assert again is not dialog and again.isVisible()
    again.close()


def test_a_notice_shows_while_a_method_loads_and_solves_its_first_frame(studio, qtbot):
    """Loading a model and the offline first frame took 2-3 s with no word."""
    import time

    from tests.stand_ins import RestPoseMethod

    class SlowToLoad(RestPoseMethod):
        name = "slow"

        def __init__(self) -> None:
            time.sleep(0.8)  # as if loading networks

    inner = studio.engine._factory
    studio.engine._factory = lambda name: SlowToLoad() if name == "slow" else inner(name)
    qtbot.waitUntil(lambda: not studio.busy.active, timeout=10000)  # the start-up notice went
    studio.session.set_method("slow")
    assert "slow" in studio.viewport.notice and "first frame" in studio.viewport.notice
    assert "slow" in studio.statusBar().currentMessage()
    qtbot.waitUntil(lambda: studio.session.latest.method == "slow", timeout=10000)
    qtbot.waitUntil(lambda: studio.viewport.notice == "", timeout=5000)
    assert "first frame" not in studio.statusBar().currentMessage()
