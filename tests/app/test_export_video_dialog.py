"""File ▸ Export video...: the dialog's options reach the video, and the studio says
where the file was written."""

from __future__ import annotations

import imageio_ffmpeg
import pytest
from PyQt6.QtCore import Qt
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
    assert dialog.options() == RenderOptions(size=(1280, 720), sensors="6", ghosts=("ik",), view="body",
                                             layout="side", truth=True, title="walk", timecode=True)  # fmt: skip
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
