"""File ▸ Export video...: the dialog's options reach the video, and the studio says
where the file was written."""

from __future__ import annotations

import imageio_ffmpeg
import pytest
from PyQt6.QtCore import QPoint, Qt
from PyQt6.QtWidgets import QDialog, QFileDialog, QMessageBox

from app.export_video_dialog import ExportVideoDialog
from app.render_scene import RenderOptions

pytestmark = pytest.mark.gui


def test_the_dialog_gives_render_options(qtbot):
    dialog = ExportVideoDialog(None, "6", ("dragposer", "ik"))
    qtbot.addWidget(dialog)
    assert dialog.options() == RenderOptions(sensors="6", view="body")  # the defaults
    dialog.size_box.setCurrentText("1280x720")
    dialog.layout_box.setCurrentText("side")
    dialog.ghosts.item(1).setCheckState(Qt.CheckState.Checked)
    dialog.truth.setChecked(True)
    dialog.timecode.setChecked(True)
    dialog.title.setText("  walk  ")
    assert dialog.options() == RenderOptions(
        size=(1280, 720),
        sensors="6",
        ghosts=("ik",),
        view="body",
        layout="side",
        truth=True,
        title="walk",
        timecode=True,
    )
    no_trackers = ExportVideoDialog(None, None, ("ik",))
    qtbot.addWidget(no_trackers)
    assert not no_trackers.ghosts.isEnabled()  # ghosts are solved from trackers


def test_export_video_renders_the_clip_and_says_it_was_written(studio, tmp_path, monkeypatch):
    out = tmp_path / "clip.mp4"

    def choose(dialog: ExportVideoDialog) -> QDialog.DialogCode:
        dialog.size_box.setCurrentText("640x360")
        dialog.view.setCurrentText("sticks")
        dialog.timecode.setChecked(True)
        return QDialog.DialogCode.Accepted

    told: list[str] = []
    monkeypatch.setattr(ExportVideoDialog, "exec", choose)
    monkeypatch.setattr(QFileDialog, "getSaveFileName", lambda *a, **k: (str(out), ""))
    monkeypatch.setattr(QMessageBox, "information", lambda parent, title, text: told.append(text))
    studio.actions_by_name["export_video"].trigger()
    frames = imageio_ffmpeg.read_frames(str(out))
    meta = next(frames)
    n = len(studio.session.motion)
    assert meta["size"] == (640, 360) and sum(1 for _ in frames) == n
    assert told == [f"Video written: {out} ({n} frames, 640x360 at {studio.session.motion.fps:g} fps)"]
    assert studio.statusBar().currentMessage() == told[0]


def _click_box(dialog: ExportVideoDialog, name: str) -> None:
    """Click the check box of ghost ``name`` in the list, where a user clicks it."""
    from PyQt6.QtTest import QTest

    item = next(
        dialog.ghosts.item(i)
        for i in range(dialog.ghosts.count())
        if dialog.ghosts.item(i).data(Qt.ItemDataRole.UserRole) == name
    )
    rect = dialog.ghosts.visualItemRect(item)
    QTest.mouseClick(
        dialog.ghosts.viewport(), Qt.MouseButton.LeftButton, pos=QPoint(rect.left() + 10, rect.center().y())
    )


def _checked(dialog: ExportVideoDialog) -> list[str]:
    return [
        dialog.ghosts.item(i).data(Qt.ItemDataRole.UserRole)
        for i in range(dialog.ghosts.count())
        if dialog.ghosts.item(i).checkState() == Qt.CheckState.Checked
    ]


def _ok(dialog: ExportVideoDialog) -> None:
    from PyQt6.QtTest import QTest
    from PyQt6.QtWidgets import QDialogButtonBox

    box = dialog.findChild(QDialogButtonBox)
    QTest.mouseClick(box.button(QDialogButtonBox.StandardButton.Ok), Qt.MouseButton.LeftButton)


def test_a_ghost_that_cannot_run_from_the_trackers_is_greyed_out_and_says_why(studio, monkeypatch):
    """RPM needs head and hands: with six trackers it cannot run, and the dialog says so
    before any file is asked for."""
    studio.session.sensors.set_preset("6")
    seen: dict = {}

    def look(dialog: ExportVideoDialog) -> int:
        dialog.show()
        _click_box(dialog, "rpm")
        seen.update(
            checked=_checked(dialog),
            note=dialog.note.text(),
            visible=dialog.note.isVisible(),
            rpm_enabled=bool(
                next(
                    dialog.ghosts.item(i)
                    for i in range(dialog.ghosts.count())
                    if dialog.ghosts.item(i).data(Qt.ItemDataRole.UserRole) == "rpm"
                ).flags()
                & Qt.ItemFlag.ItemIsEnabled
            ),
        )
        dialog.reject()
        return dialog.result()

    monkeypatch.setattr(ExportVideoDialog, "exec", look)
    monkeypatch.setattr(QFileDialog, "getSaveFileName", lambda *a, **k: pytest.fail("no file dialog on cancel"))
    studio.actions_by_name["export_video"].trigger()
    # ik ticked as the method on screen (the first export: a video of what the user sees)
    assert seen["checked"] == ["ik"] and not seen["rpm_enabled"]
    assert seen["visible"] and "rpm runs only with tracker preset '3-head-hands'" in seen["note"], seen


def test_ok_checks_the_options_before_the_file_dialog_and_stays_open_on_a_refusal(studio, monkeypatch):
    studio.session.sensors.set_preset("6")
    seen: dict = {}

    def force_rpm(dialog: ExportVideoDialog) -> int:
        dialog.show()
        for i in range(dialog.ghosts.count()):  # a choice the list does not offer: OK must still refuse it
            if dialog.ghosts.item(i).data(Qt.ItemDataRole.UserRole) == "rpm":
                dialog.ghosts.item(i).setCheckState(Qt.CheckState.Checked)
        _ok(dialog)
        seen.update(open=dialog.isVisible(), note=dialog.note.text())
        dialog.reject()
        return dialog.result()

    monkeypatch.setattr(ExportVideoDialog, "exec", force_rpm)
    monkeypatch.setattr(QFileDialog, "getSaveFileName", lambda *a, **k: pytest.fail("file dialog after a refusal"))
    studio.actions_by_name["export_video"].trigger()
    assert seen["open"] and "--ghosts rpm: rpm runs only with tracker preset '3-head-hands'" in seen["note"], seen


def test_the_dialog_remembers_the_last_choices(studio, monkeypatch):
    studio.session.sensors.set_preset("6")
    shown: list[dict] = []

    def choose(dialog: ExportVideoDialog) -> int:
        dialog.show()
        shown.append(
            {
                "size": dialog.size_box.currentText(),
                "view": dialog.view.currentText(),
                "timecode": dialog.timecode.isChecked(),
                "title": dialog.title.text(),
                "ghosts": _checked(dialog),
            }
        )
        if len(shown) == 1:
            dialog.size_box.setCurrentText("640x360")
            dialog.view.setCurrentText("sticks")
            dialog.timecode.setChecked(True)
            dialog.title.setText("walk")
            _click_box(dialog, "ik")  # the method on screen, ticked the first time: off
        _ok(dialog)
        return dialog.result()

    monkeypatch.setattr(ExportVideoDialog, "exec", choose)
    monkeypatch.setattr(QFileDialog, "getSaveFileName", lambda *a, **k: ("", ""))  # then cancel the file
    studio.actions_by_name["export_video"].trigger()
    studio.actions_by_name["export_video"].trigger()
    assert shown[0] == {"size": "960x540", "view": "body", "timecode": False, "title": "", "ghosts": ["ik"]}
    assert shown[1] == {"size": "640x360", "view": "sticks", "timecode": True, "title": "walk", "ghosts": []}
