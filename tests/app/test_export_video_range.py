"""Export video of a part of the clip, and a Cancel that stops the render and leaves no
file: in the dialog, in ``render --start/--end``, and for the ghosts solved beside it."""

from __future__ import annotations

import time

import imageio_ffmpeg
import numpy as np
import pytest
from PyQt6.QtCore import QTimer
from PyQt6.QtWidgets import QApplication, QDialog, QFileDialog, QMessageBox, QProgressDialog, QPushButton

from app.export_video_dialog import ExportVideoDialog
from app.render import main, render_video
from app.render_scene import FrameRenderer, RenderOptions
from engine.motion.bvh import save_motion_bvh
from engine.progress import Cancelled

pytestmark = pytest.mark.gui

#: What the status bar says of a cancelled video.
CANCELLED = "Export cancelled: no video was written"


def frame_count(path) -> int:
    frames = imageio_ffmpeg.read_frames(str(path))
    next(frames)
    return sum(1 for _ in frames)


def test_the_range_starts_as_the_whole_clip_or_the_timeline_selection_and_is_bounded(qtbot):
    whole = ExportVideoDialog(None, "6", ("ik",), num_frames=120, fps=60.0)
    qtbot.addWidget(whole)
    assert (whole.first.value(), whole.last.value()) == (0, 119) and whole.options().frames is None
    assert whole.last.maximum() == 119 and "the whole clip" in whole.frames_note.text()
    whole.last.setValue(500)  # beyond the clip: held at its last frame
    whole.first.setValue(30)
    whole.last.setValue(10)  # before the first: held at it
    assert whole.options().frames == (30, 30)
    whole.whole.click()
    assert whole.options().frames is None
    picked = ExportVideoDialog(None, "6", ("ik",), num_frames=120, fps=60.0, selection=(90, 40))
    qtbot.addWidget(picked)
    assert picked.options().frames == (40, 90)
    assert picked.frames_note.text() == "51 frames, 0.85 s: the timeline's selection, of frames 0-119"
    assert "first frame" in picked.first.toolTip()  # the ghosts start there: said where it is chosen


def test_export_video_writes_the_timeline_selection_with_the_clips_frame_numbers(studio, tmp_path, monkeypatch):
    out = tmp_path / "part.mp4"
    studio.timeline.set_selection(10, 19)
    told: list[str] = []

    def choose(dialog: ExportVideoDialog) -> QDialog.DialogCode:
        assert dialog.options().frames == (10, 19)  # the selection, offered
        dialog.size_box.setCurrentText("640x360")
        dialog.view.setCurrentText("sticks")
        dialog.timecode.setChecked(True)
        return QDialog.DialogCode.Accepted

    shown: list[str] = []
    pose = FrameRenderer.pose

    def posing(self, f, ghosts=None):
        pose(self, f, ghosts)
        shown.append(self.texts.time.GetInput())

    monkeypatch.setattr(FrameRenderer, "pose", posing)
    monkeypatch.setattr(ExportVideoDialog, "exec", choose)
    monkeypatch.setattr(QFileDialog, "getSaveFileName", lambda *a, **k: (str(out), ""))
    monkeypatch.setattr(QMessageBox, "information", lambda parent, title, text: told.append(text))
    studio.actions_by_name["export_video"].trigger()
    assert frame_count(out) == 10
    last = len(studio.session.motion) - 1
    assert shown[0] == f"00:00.17  frame 10/{last}" and shown[-1] == f"00:00.32  frame 19/{last}"
    assert told == [f"Video written: {out} (frames 10-19: 10 frames, 640x360 at 60 fps)"]


def press_cancel_at(frame: int, monkeypatch) -> list[int]:
    """Click the progress dialog's Cancel as frame ``frame`` is posed; the frames posed."""
    posed: list[int] = []
    pose = FrameRenderer.pose

    def click() -> None:
        (dialog,) = [w for w in QApplication.topLevelWidgets() if isinstance(w, QProgressDialog)]
        (button,) = [b for b in dialog.findChildren(QPushButton) if b.text() == "Cancel"]
        button.click()

    def posing(self, f, ghosts=None):
        posed.append(f)
        if f == frame:
            QTimer.singleShot(0, click)  # on the event loop the render lets run, as a user's click
        pose(self, f, ghosts)

    monkeypatch.setattr(FrameRenderer, "pose", posing)
    return posed


def test_cancel_stops_the_render_leaves_no_file_and_says_so(studio, tmp_path, monkeypatch):
    folder = tmp_path / "videos"
    folder.mkdir()
    out = folder / "v.mp4"
    posed = press_cancel_at(5, monkeypatch)
    monkeypatch.setattr(ExportVideoDialog, "exec", lambda self: QDialog.DialogCode.Accepted)
    monkeypatch.setattr(QFileDialog, "getSaveFileName", lambda *a, **k: (str(out), ""))
    from app.authoring_actions import export_video

    # no message box at all (the fixture fails on any): the status bar says it
    assert export_video(studio) is None
    assert posed[-1] <= 6 < len(studio.session.motion)  # stopped at once
    assert list(folder.iterdir()) == []  # no video, no temporary file
    assert studio.statusBar().currentMessage() == CANCELLED
    assert not [w for w in QApplication.topLevelWidgets() if isinstance(w, QProgressDialog) and w.isVisible()]


def test_cancel_while_waiting_for_the_ghosts_stops_promptly_and_ends_their_process(synthetic_motion, tmp_path):
    """The ghosts' process takes seconds to start: Cancel is answered meanwhile."""
    import multiprocessing as mp

    t0 = time.monotonic()
    with pytest.raises(Cancelled):
        render_video(
            synthetic_motion.slice(0, 40),
            tmp_path / "v.mp4",
            RenderOptions(size=(64, 48), sensors="6", ghosts=("ik",)),
            cancelled=lambda: time.monotonic() > t0 + 0.3,
        )
    assert time.monotonic() - t0 < 3.0
    assert list(tmp_path.iterdir()) == [] and not mp.active_children()


def test_ghosts_solve_the_range_alone_from_its_first_frame(synthetic_motion, tmp_path, monkeypatch):
    import engine.studio.ghost_solve as gs

    given = []

    class Recorded:
        def __init__(self, motion, sensors, methods):
            given.append(motion)
            self.pos = motion.positions()

        def positions(self, frame, cancelled=None):
            return {"ik": self.pos[frame]}

        def close(self):
            pass

    monkeypatch.setattr(gs, "GhostSolves", Recorded)
    out = tmp_path / "v.mp4"
    options = RenderOptions(size=(64, 48), sensors="6", ghosts=("ik",), frames=(20, 29))
    render_video(synthetic_motion, out, options)
    (part,) = given
    assert len(part) == 10 and np.array_equal(part.local_rot, synthetic_motion.local_rot[20:30])
    assert frame_count(out) == 10


def test_render_start_end_on_the_command_line(synthetic_motion, tmp_path, capsys):
    clip = tmp_path / "walk.bvh"
    save_motion_bvh(clip, synthetic_motion.slice(0, 40))
    out = tmp_path / "v.mp4"
    assert main([str(clip), "--out", str(out), "--size", "64x48", "--start", "5", "--end", "14", "--no-progress"]) == 0
    assert frame_count(out) == 10 and "10 frames (frames 5-14 of 40)" in capsys.readouterr().out
    for args, said in (
        (["--end", "40"], "--end 40: the clip's frames are 0-39"),
        (["--start", "-1"], "--start -1: frames are counted from 0"),
        (["--start", "9", "--end", "3"], "--end 3 is before --start 9"),
    ):
        bad = tmp_path / "bad.mp4"
        assert main([str(clip), "--out", str(bad), *args, "--no-progress"]) == 2
        err = capsys.readouterr().err
        assert err.startswith("error: ") and said in err and err.count("\n") == 1, err
        assert not bad.exists()


def test_the_range_is_the_timelines_frames_at_another_rate():
    """The studio opens clips at 60 fps: a 120 fps video of frames 100-200 is the same time."""
    from app.render import timeline_range
    from engine.motion.clip import Motion

    at_120 = Motion(np.tile([1.0, 0, 0, 0], (1199, 22, 1)), np.zeros((1199, 3)), fps=120.0)
    assert timeline_range(100, 200, at_120, 60.0) == (200, 400)
    assert timeline_range(None, 599, at_120, 60.0) == (0, 1198)
    assert timeline_range(None, None, at_120, 60.0) is None
    with pytest.raises(Exception, match="--start 600: the clip's frames are 0-599"):
        timeline_range(600, None, at_120, 60.0)


def test_the_pose_window_exports_a_range_of_its_bake(pose_window, tmp_path, monkeypatch):
    from tests.app.test_pose_window import key_the_wrist

    w = pose_window
    key_the_wrist(w, (0, [0.0, -0.15, 0.05]), (20, [0.1, -0.1, 0.35]), length=21)
    out = tmp_path / "pose.mp4"

    def choose(dialog: ExportVideoDialog) -> QDialog.DialogCode:
        assert not dialog.ghosts.isEnabled() and dialog.last.maximum() == 20
        dialog.size_box.setCurrentText("640x360")
        dialog.set_frames(5, 12)
        return QDialog.DialogCode.Accepted

    told: list[str] = []
    monkeypatch.setattr(ExportVideoDialog, "exec", choose)
    monkeypatch.setattr(QFileDialog, "getSaveFileName", lambda *a, **k: (str(out), ""))
    monkeypatch.setattr(QMessageBox, "information", lambda parent, title, text: told.append(text))
    w.files.export_video_dialog()
    assert frame_count(out) == 8 and told and "frames 5-12: 8 frames" in told[0]
