"""Autosave and recovery (app/autosave.py, docs/reliability.md) with real windows: edits
reach the autosave file within its interval; after a crash (a killed studio process, or a
pose window dropped without closing) the next start recovers exactly that state; a clean
close removes the file."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys

import numpy as np
import pytest

from engine import skeleton as sk
from engine.autosave import AutosaveSession, left_sessions
from tests.app.gui_helpers import close_now, scrub
from tests.conftest import REPO
from tests.engine.authoring.test_recovery import same

pytestmark = pytest.mark.gui
INTERVAL_MS = 200


def wait_saved(qtbot, auto) -> None:
    """Until ``auto`` (a DocumentAutosave) has written what changed last."""
    if auto.timer.isActive():
        with qtbot.waitSignal(auto.saved, timeout=10000):
            pass


def test_pose_window_edits_are_recovered_exactly_after_a_crash(pose_window, qtbot, tmp_path):
    from app.autosave import recover_pose, watch_pose

    w = pose_window
    files = AutosaveSession(tmp_path)
    auto = watch_pose(files, w, "pose1", interval_ms=INTERVAL_MS)
    assert not files.path("pose1").exists()  # nothing unsaved yet
    start = w.mode.pose.positions[sk.JOINT_INDEX["lwrist"]].copy()
    w.drag_joint("lwrist", start + [0.05, -0.1, 0.15])
    with qtbot.waitSignal(auto.saved, timeout=10000):  # the first edit is on disk within the interval
        pass
    w.add_key(0)
    w.keys.length.setValue(60)
    w.turn_body(40.0)
    w.add_key(30)
    w.go_to(12)  # between the keys: the baked in-between, its interpolated targets
    w.drag_joint("rwrist", w.mode.pose.positions[sk.JOINT_INDEX["rwrist"]] + [0.0, 0.0, 0.1])  # not keyed
    wait_saved(qtbot, auto)
    written = w.session.state()
    files.abandon()  # the process dies: its lock goes, its files stay

    [left] = left_sessions(tmp_path)
    assert set(left.documents) == {"pose1"}
    back = recover_pose(None, left.read("pose1")[0], str(left.documents["pose1"]))
    try:
        assert same(written, back.session.state()) and back.frame == 12 == w.frame
        assert back.dirty and back.mode.character.height == pytest.approx(w.mode.character.height)
        assert [k.frame for k in back.scene.keys] == [0, 30] and back.scene.animation.frames == 60
        assert back.keys.length.value() == 60 and list(back.targets.rows) == list(w.targets.rows)
        label = back.keys.label.text()  # the edit is said not keyed, as before the crash
        assert label == w.keys.label.text() and label.startswith("frame 12 · unkeyed edit"), label
        scrub(back, 20)  # leaving drops it, one undo step
        assert back.frame == 20 and "frame 12" in back.statusBar().currentMessage()
        back.actions_by_name["undo"].trigger()
        assert back.frame == 12 and same(written, back.session.state())
        assert back.keys.label.text().startswith("frame 12 · unkeyed edit")
    finally:
        close_now(back)
    w.close()  # a close on purpose (the fixture answers Discard) removes the file
    assert not files.path("pose1").exists() and auto.closed


def test_a_saved_pose_window_has_no_autosave(pose_window, qtbot, tmp_path):
    from app.autosave import watch_pose

    w = pose_window
    files = AutosaveSession(tmp_path)
    auto = watch_pose(files, w, "pose1", interval_ms=INTERVAL_MS)
    w.drag_joint("lwrist", w.mode.pose.positions[sk.JOINT_INDEX["lwrist"]] + [0.0, -0.1, 0.1])
    wait_saved(qtbot, auto)
    assert files.path("pose1").is_file()
    w.files.save(tmp_path / "scene.json")
    wait_saved(qtbot, auto)
    assert not files.path("pose1").exists()
    files.close()


def run_child(tmp_path, clip, end: str) -> subprocess.CompletedProcess:
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([str(REPO), os.environ.get("PYTHONPATH", "")])}
    return subprocess.run(
        [
            sys.executable,
            "-m",
            "tests.app.autosave_child",
            str(tmp_path / "state"),
            str(clip),
            str(tmp_path / "expected"),
            end,
        ],
        env=env,
        cwd=REPO,
        timeout=300,
        capture_output=True,
        text=True,
    )


@pytest.fixture
def walk(tmp_path, synthetic_motion):
    from engine.motion.bvh import save_motion_bvh

    clip = tmp_path / "walk.bvh"
    save_motion_bvh(clip, synthetic_motion)
    return clip


@pytest.mark.slow
def test_a_killed_studio_is_recovered_exactly_at_the_next_start(studio, qtbot, tmp_path, walk):
    from app import autosave
    from app.clip_saving import clip_edited
    from app.main import start_autosave

    child = run_child(tmp_path, walk, "kill")
    assert child.returncode == -signal.SIGKILL, child.stderr[-3000:]
    expected = json.loads((tmp_path / "expected.json").read_text())
    arrays = np.load(tmp_path / "expected.npz")
    [left] = left_sessions(tmp_path / "state")
    assert set(left.documents) == {"studio"}

    files = start_autosave(studio, tmp_path / "state")  # the next start
    box = autosave.offer(studio, left_sessions(tmp_path / "state"))
    assert box is not None and "did not quit cleanly" in box.text()
    next(b for b in box.buttons() if b.text() == "Recover last session").click()
    s = studio.session
    assert s.to_scene() == expected and s.frame == 20
    assert np.array_equal(s.motion.local_rot, arrays["local_rot"]) and np.array_equal(
        s.motion.root_pos, arrays["root_pos"]
    )
    assert clip_edited(studio) and not studio.undo.is_clean()
    assert not any(p.exists() for p in left.documents.values())  # taken over by this session
    assert files.path("studio").is_file() and files.path("studio", ".npz").is_file()
    studio.undo.history.undo()  # one step back to the session as it started
    assert not clip_edited(studio) and s.to_scene() != expected
    studio.undo.set_clean()
    files.close()


@pytest.mark.slow
def test_a_studio_that_quits_cleanly_leaves_nothing_to_recover(tmp_path, walk):
    child = run_child(tmp_path, walk, "quit")
    assert child.returncode == 0, child.stderr[-3000:]
    assert (tmp_path / "expected.json").is_file()  # it had unsaved edits, autosaved
    assert left_sessions(tmp_path / "state") == []
    assert not list((tmp_path / "state").glob("autosave-*"))


def test_discard_removes_what_was_left(studio, tmp_path):
    from app import autosave

    files = AutosaveSession(tmp_path)
    files.write("studio", studio.session.to_scene())
    files.abandon()
    box = autosave.offer(studio, left_sessions(tmp_path))
    next(b for b in box.buttons() if b.text() == "Discard").click()
    assert left_sessions(tmp_path) == [] and not list(tmp_path.glob("autosave-*"))
    assert studio.undo.is_clean()
    assert autosave.offer(studio, []) is None


def test_recovery_reopens_the_pose_windows_autosaved_with_the_studio(studio, qtbot, tmp_path, vae):
    from app import autosave
    from app.main import start_autosave
    from engine.authoring.pose_mode import PoseMode
    from engine.authoring.recovery import document
    from engine.authoring.session import AuthoringSession

    made = AuthoringSession(PoseMode(vae, 1.7))
    made.drag_joint("lwrist", made.pose.positions[sk.JOINT_INDEX["lwrist"]] + [0.0, -0.1, 0.1])
    made.add_key(5)
    crashed = AutosaveSession(tmp_path)
    crashed.write("pose2", json.loads(json.dumps(document(made))))
    crashed.abandon()
    files = start_autosave(studio, tmp_path)
    [left] = left_sessions(tmp_path)
    assert autosave.recover(studio, left) == []
    [pose] = studio.pose_windows
    try:
        assert same(made.state(), pose.session.state()) and pose.isVisible()
        assert pose.autosave is not None and files.path("pose1").is_file()  # on disk under this session
        assert not left.documents["pose2"].exists()
    finally:
        close_now(pose)
    assert not files.path("pose1").exists()
    files.close()
