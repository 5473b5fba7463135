"""A misspelt scene key (``keys`` as ``keyz``) is refused by the one scene validator in
the studio's Load scene, the pose window's Open scene and ``gui --scene`` alike: a
message naming the file, the key and the nearest known key, and nothing changes."""

from __future__ import annotations

import json

import pytest
from PyQt6.QtCore import Qt
from PyQt6.QtTest import QTest
from PyQt6.QtWidgets import QApplication, QFileDialog, QMessageBox

from tests.app.test_gui_scene_cli import _gui, scene_file  # noqa: F401 (fixture)

pytestmark = pytest.mark.gui

MEANT = "unknown field 'keyz' (did you mean 'keys'?)"


@pytest.fixture
def misspelt(tmp_path):
    path = tmp_path / "keyz.json"
    path.write_text(
        json.dumps(
            {
                "format": "dragposer-scene",
                "version": 2,
                "animation": {"frames": 61},
                "constraints": [{"kind": "floor", "name": "floor"}],
                "keyz": [{"frame": 0, "targets": {"lwrist": [0.3, -0.2, 1.2]}}],
            }
        )
    )
    return path


def _press(window, key, mods=Qt.KeyboardModifier.NoModifier):
    window.windowHandle().requestActivate()
    QApplication.processEvents()
    QTest.keyClick(window, key, mods)


def test_load_scene_in_the_studio_shows_the_misspelt_key_in_a_dialog_and_changes_nothing(
    studio, misspelt, monkeypatch, qtbot
):
    shown = []
    monkeypatch.setattr(QMessageBox, "critical", lambda *a, **k: shown.append(a[2]))
    monkeypatch.setattr(QFileDialog, "getOpenFileName", lambda *a, **k: (str(misspelt), ""))
    before = [c.to_dict() for c in studio.session.constraints]
    steps = studio.undo.history.count()
    _press(studio, Qt.Key.Key_L, Qt.KeyboardModifier.ControlModifier)  # File > Load scene
    qtbot.waitUntil(lambda: bool(shown), timeout=5000)
    assert len(shown) == 1 and str(misspelt) in shown[0] and MEANT in shown[0], shown
    assert [c.to_dict() for c in studio.session.constraints] == before and studio.undo.history.count() == steps


def test_open_scene_in_the_pose_window_shows_the_misspelt_key_and_keeps_the_keys(
    pose_window, misspelt, monkeypatch, qtbot
):
    w = pose_window
    w.add_key(0)
    w.session.history.set_clean()
    shown = []
    monkeypatch.setattr(QMessageBox, "warning", lambda *a, **k: shown.append(a[2]))
    monkeypatch.setattr(QFileDialog, "getOpenFileName", lambda *a, **k: (str(misspelt), ""))
    _press(w, Qt.Key.Key_O, Qt.KeyboardModifier.ControlModifier)  # File > Open scene
    qtbot.waitUntil(lambda: bool(shown), timeout=5000)
    assert len(shown) == 1 and str(misspelt) in shown[0] and MEANT in shown[0], shown
    assert [k.frame for k in w.scene.keys] == [0] and not w.scene.constraints


def test_gui_scene_with_a_misspelt_key_is_one_line_and_exit_2(tmp_path, scene_file, misspelt):  # noqa: F811
    clip, _ = scene_file
    done = _gui(
        tmp_path, str(clip), "--method", "ik", "--scene", str(misspelt), "--screenshot", str(tmp_path / "x.png")
    )
    assert done.returncode == 2, done.stderr[-2000:]
    lines = [ln for ln in done.stderr.splitlines() if ln.strip()]
    assert len(lines) == 1 and "keyz.json" in lines[0] and MEANT in lines[0], done.stderr
    assert not (tmp_path / "x.png").exists()
