"""The studio's unsaved-changes prompt: on quit, on opening another clip or scene, after edits."""

from __future__ import annotations

import json

import numpy as np
import pytest

pytestmark = pytest.mark.gui


@pytest.fixture
def answer(monkeypatch):
    """Answer the prompt with ``answer.next`` ("Save", "Discard", "Cancel"); ``answer.asked`` lists each prompt."""
    from PyQt6.QtWidgets import QMessageBox

    class Answer:
        next = "Cancel"
        asked: list[str] = []

    def question(parent, title, text, buttons):
        Answer.asked.append(text)
        assert buttons & QMessageBox.StandardButton.Save and buttons & QMessageBox.StandardButton.Discard
        return getattr(QMessageBox.StandardButton, Answer.next)

    monkeypatch.setattr(QMessageBox, "question", question)
    return Answer


def _save_to(monkeypatch, paths: list):
    from PyQt6.QtWidgets import QFileDialog

    monkeypatch.setattr(QFileDialog, "getSaveFileName", lambda *a, **k: (str(paths.pop(0)), ""))


def test_quit_with_no_edits_does_not_ask(studio, answer):
    assert studio.close() and answer.asked == []


def test_quit_after_a_constraint_edit_asks_and_cancel_keeps_the_window(studio, answer, qtbot):
    studio.session.constraints.add("floor")
    answer.next = "Cancel"
    assert not studio.close() and studio.isVisible() and studio.engine.is_alive()
    assert len(answer.asked) == 1 and "before quitting" in answer.asked[0]
    answer.next = "Discard"
    assert studio.close() and not studio.engine.is_alive()


def test_quit_save_writes_the_scene(studio, answer, monkeypatch, tmp_path):
    studio.session.constraints.add("floor")
    _save_to(monkeypatch, [tmp_path / "s.json"])
    answer.next = "Save"
    assert studio.close()
    assert [c["kind"] for c in json.loads((tmp_path / "s.json").read_text())["constraints"]] == ["floor"]


def test_opening_a_clip_after_a_range_resolve_asks_cancel_keeps_save_writes_both(
    studio, answer, monkeypatch, tmp_path, synthetic_motion, qtbot
):
    from app.range_actions import resolve_range
    from engine.motion.bvh import save_motion_bvh
    from engine.studio.clips import load_clip

    other = tmp_path / "other.bvh"
    save_motion_bvh(other, synthetic_motion)
    edited = resolve_range(studio, 30, 50, blend=4).wait().motion
    answer.next = "Cancel"
    assert not studio.files.open_path(other)
    assert studio.session.motion is edited and "re-solved clip" in answer.asked[-1]
    _save_to(monkeypatch, [tmp_path / "edited.bvh", tmp_path / "scene.json"])
    answer.next = "Save"
    assert studio.files.open_path(other)
    assert studio.session.path == other and studio.undo.is_clean()

    def rel(m):  # loading re-floors the clip: compare poses about the first root
        p = m.positions()
        return p - p[:1, :1]

    saved = rel(load_clip(tmp_path / "edited.bvh"))
    assert np.allclose(saved, rel(edited), atol=1e-4)  # the edit, not the original
    assert not np.allclose(saved[30:51], rel(synthetic_motion)[30:51], atol=1e-3)
    assert (tmp_path / "scene.json").exists()
    qtbot.waitUntil(lambda: studio.session.latest is not None, timeout=10000)


def test_loading_a_scene_after_an_edit_asks_and_discard_loads_it(studio, answer, tmp_path):
    scene = tmp_path / "s.json"
    scene.write_text(json.dumps({"format": "dragposer-scene", "version": 1, "constraints": []}))
    studio.session.constraints.add("floor")
    answer.next = "Cancel"
    assert not studio.files.load_scene(str(scene)) and len(studio.session.constraints) == 1
    answer.next = "Discard"
    assert studio.files.load_scene(str(scene)) and list(studio.session.constraints) == []
    assert studio.undo.is_clean() and "loading another scene" in answer.asked[-1]


def test_opening_a_tracker_recording_after_an_edit_asks_first(studio, answer, monkeypatch):
    from PyQt6.QtWidgets import QFileDialog

    asked_for_file = []
    monkeypatch.setattr(QFileDialog, "getOpenFileName", lambda *a, **k: asked_for_file.append(a) or ("", ""))
    studio.session.constraints.add("floor")
    answer.next = "Cancel"
    studio.live.open_recording_dialog()
    assert asked_for_file == [] and "tracker recording" in answer.asked[-1]
    answer.next = "Discard"
    studio.live.open_recording_dialog()
    assert len(asked_for_file) == 1


def _quit_action(studio):
    file_menu = studio.menuBar().actions()[0].menu()
    return next(a for a in file_menu.actions() if a.text() == "&Quit")


def test_quit_asks_an_open_pose_window_with_unsaved_keys_and_ends_the_app(studio, answer, qtbot):
    from PyQt6.QtWidgets import QApplication

    from app.authoring_actions import open_pose_window
    from tests.app.gui_helpers import close_now

    pose = open_pose_window(studio, 1.7, from_clip=False)
    try:
        pose.add_key(0)
        answer.next = "Cancel"
        _quit_action(studio).trigger()
        assert studio.isVisible() and pose.isVisible() and studio.engine.is_alive()
        assert len(answer.asked) == 1 and "keys and targets before quitting" in answer.asked[0]
        assert pose.dirty and pose.session.scene.keys  # Cancel kept the keys

        answer.next = "Discard"
        _quit_action(studio).trigger()
        assert not studio.isVisible() and not pose.isVisible() and not studio.engine.is_alive()
        # no window left open: Qt ends the app's event loop when its last window closes
        assert not [w for w in QApplication.topLevelWidgets() if w.isVisible()]
        assert len(answer.asked) == 2  # asked once, not again by the pose window's own close
    finally:
        if pose.isVisible():
            close_now(pose)


def test_quit_cancelled_in_the_studio_keeps_the_pose_window_open_too(studio, monkeypatch):
    from PyQt6.QtWidgets import QMessageBox

    from app.authoring_actions import open_pose_window
    from tests.app.gui_helpers import close_now

    pose = open_pose_window(studio, 1.7, from_clip=False)
    try:
        pose.add_key(0)
        studio.session.constraints.add("floor")
        asked = []

        def discard_pose_then_cancel_studio(parent, title, text, buttons):
            asked.append(parent)
            return QMessageBox.StandardButton.Discard if parent is pose else QMessageBox.StandardButton.Cancel

        monkeypatch.setattr(QMessageBox, "question", discard_pose_then_cancel_studio)
        _quit_action(studio).trigger()
        assert asked == [pose, studio]
        assert studio.isVisible() and pose.isVisible() and pose.session.scene.keys
    finally:
        close_now(pose)


def test_quit_while_a_pose_window_bakes_cancels_it_and_leaves_no_message_behind(studio, answer, qtbot, monkeypatch):
    """Quitting while a pose window waits on its bake (scrubbed between keys) cancels the
    bake; a "the bake did not finish" box over no window would keep the process running
    until clicked away, so none is shown."""
    from PyQt6.QtCore import QTimer
    from PyQt6.QtWidgets import QApplication, QMessageBox

    from app.authoring_actions import open_pose_window
    from tests.app.gui_helpers import close_now

    pose = open_pose_window(studio, 1.7, from_clip=False)
    try:
        pose.keys.length.setValue(151)
        pose.add_key(0)
        pose.go_to(150)
        pose.add_key(150)
        pose.session.history.set_clean()  # saved: the quit asks nothing
        shown = []
        monkeypatch.setattr(QMessageBox, "warning", lambda *a, **k: shown.append(a[2]))
        quit_during_bake = QTimer(interval=10)
        quit_during_bake.timeout.connect(
            lambda: (
                pose.jobs.running and pose.jobs.done >= 3 and (quit_during_bake.stop(), _quit_action(studio).trigger())
            )
        )
        quit_during_bake.start()
        pose.go_to(75)  # between the keys: waits on the bake, during which the studio quits
        quit_during_bake.stop()
        QApplication.processEvents()
        assert not studio.isVisible() and not pose.isVisible() and not pose.jobs.running
        assert shown == [] and answer.asked == []
    finally:
        if pose.isVisible():
            close_now(pose)


def test_a_discarded_preset_does_not_come_back_at_the_next_start(studio, answer, tmp_path, synthetic_motion):
    """A preset chosen in the sensor panel is remembered for the next session only when
    the scene is kept (saved): one undone, or discarded when asked, is not."""
    from PyQt6.QtCore import QSettings

    from app.main import open_initial
    from engine.motion.bvh import save_motion_bvh

    studio.settings.setValue("last_preset", "6")
    open_initial(studio, None, None)
    panel = studio.sensor_panel.preset
    panel.setCurrentText("3-head-hands")
    assert studio.session.preset == "3-head-hands"
    studio.undo.history.undo()
    assert studio.session.preset == "6" and studio.undo.is_clean()
    assert studio.settings.value("last_preset") == "6"  # undone: not remembered
    panel.setCurrentText("4")
    other = tmp_path / "other.bvh"
    save_motion_bvh(other, synthetic_motion.slice(0, 30))
    answer.next = "Discard"
    assert studio.files.open_path(other)  # discarded before another clip: not remembered
    assert studio.settings.value("last_preset") == "6"
    panel.setCurrentText("5")
    assert studio.files.save_scene(str(tmp_path / "s.json"))  # kept: remembered
    assert studio.settings.value("last_preset") == "5"
    panel.setCurrentText("4")
    assert studio.close()  # discarded when quitting: the saved one stays
    studio.settings.sync()
    assert QSettings(studio.settings.fileName(), QSettings.Format.IniFormat).value("last_preset") == "5"
