"""Save dialogs start in a folder the user can write in: the one last saved into, else
the source's when writable, else home; a reconstruction into a folder that cannot be
written is refused before the clip is re-solved."""

from __future__ import annotations

import os
from pathlib import Path

import pytest
from PyQt6.QtCore import QSettings
from PyQt6.QtWidgets import QFileDialog

pytestmark = pytest.mark.gui


@pytest.fixture
def home(tmp_path, monkeypatch) -> Path:
    home = tmp_path / "home"
    home.mkdir()
    monkeypatch.setattr(Path, "home", staticmethod(lambda: home))
    return home


def read_only(monkeypatch, *folders: Path) -> None:
    """The tests run as root, who may write anywhere: ``folders`` read as read-only."""
    access = os.access
    monkeypatch.setattr(os, "access", lambda p, mode: Path(p) not in folders and access(p, mode))


def test_the_folder_last_saved_into_then_a_writable_source_then_home(tmp_path, home, monkeypatch):
    import app.save_folder as sf
    from app.save_folder import save_folder

    settings = QSettings(str(tmp_path / "s.ini"), QSettings.Format.IniFormat)
    data, mine = tmp_path / "data", tmp_path / "mine"
    data.mkdir()
    mine.mkdir()
    clip = data / "walk.bvh"
    assert save_folder(settings, clip) == data  # writable: beside the clip
    read_only(monkeypatch, data)
    assert save_folder(settings, clip) == home  # read-only: home
    assert save_folder(settings, sf.APP_ASSETS / "clips" / "example.bvh") == home  # not the studio's own files
    sf.remember_save_folder(settings, mine / "x.bvh")
    assert save_folder(settings, clip) == mine and save_folder(None, clip) == home
    mine.rmdir()  # gone: the next choice
    assert save_folder(settings, clip) == home


def test_every_studio_save_dialog_offers_the_folder_last_saved_into(
    studio, tmp_path, home, monkeypatch, synthetic_motion
):
    from app.authoring_actions import export_video
    from app.clip_saving import save_clip_dialog
    from app.export_video_dialog import ExportVideoDialog
    from engine.motion.bvh import save_motion_bvh

    shared, mine = tmp_path / "shared", tmp_path / "mine"
    shared.mkdir()
    mine.mkdir()
    save_motion_bvh(shared / "run.bvh", synthetic_motion.slice(0, 30))
    read_only(monkeypatch, shared)
    assert studio.files.open_path(str(shared / "run.bvh"))
    offered: list[str] = []
    answers = [str(mine / "first_scene.json")]
    monkeypatch.setattr(
        QFileDialog,
        "getSaveFileName",
        lambda *a, **k: (offered.append(a[2]), (answers.pop(0) if answers else "", ""))[1],
    )
    studio.files.save_scene()  # read-only clip folder, nothing remembered: home
    assert offered == [str(home / "run_scene.json")] and (mine / "first_scene.json").exists()
    from PyQt6.QtWidgets import QDialog

    monkeypatch.setattr(ExportVideoDialog, "exec", lambda self: QDialog.DialogCode.Accepted)
    studio.files.save_scene()
    studio.files.export_screenshot()
    studio.files.save_reconstruction()
    export_video(studio)
    save_clip_dialog(studio)
    name = studio.session.method
    assert offered[1:] == [
        str(mine / "run_scene.json"),
        str(mine / "run_studio.png"),
        str(mine / f"run_{name}.bvh"),
        str(mine / "run_video.mp4"),
        str(mine / "run_edited.bvh"),
    ]


def test_a_reconstruction_into_a_read_only_folder_is_refused_before_the_solve(studio, tmp_path, monkeypatch):
    locked = tmp_path / "locked"
    locked.mkdir()
    read_only(monkeypatch, locked)
    errors: list[tuple[str, str]] = []
    monkeypatch.setattr(studio.files, "show_error", lambda title, text: errors.append((title, text)))
    monkeypatch.setattr(QFileDialog, "getSaveFileName", lambda *a, **k: (str(locked / "rec.bvh"), ""))
    studio.files.save_reconstruction()
    assert not studio.files.export.running  # nothing solved
    assert errors == [
        (
            "Cannot save reconstruction",
            f"cannot write in {locked}: the folder is not writable; choose another folder",
        )
    ]


def test_the_pose_window_shares_the_memory(home, pose_window, tmp_path):
    w = pose_window
    assert w.files.suggested(".json") == str(home / "pose.json")
    mine = tmp_path / "mine"
    mine.mkdir()
    w.settings.setValue("files/save_folder", str(mine))  # saved into from the studio
    assert w.files.suggested(".bvh") == str(mine / "pose.bvh")
