"""Autosave files (engine/autosave.py): written atomically, removed by a clean quit,
found after a program that held them died, read back exactly."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys

import numpy as np
import pytest

from engine.autosave import AutosaveSession, left_sessions, load_clip
from engine.errors import UserError


def test_a_clean_quit_leaves_nothing_and_a_running_session_is_not_left(tmp_path):
    a = AutosaveSession(tmp_path)
    a.write("studio", {"frame": 3})
    assert left_sessions(tmp_path) == []  # its program (this one) still holds the lock
    a.close()
    assert list(tmp_path.iterdir()) == []


def test_an_abandoned_session_is_found_with_its_documents_and_edited_clip(tmp_path, synthetic_motion):
    a = AutosaveSession(tmp_path)
    a.write("studio", {"frame": 3, "clip": "walk.bvh"}, clip=synthetic_motion)
    a.write("pose1", {"keys": []})
    a.abandon()
    [left] = left_sessions(tmp_path)
    assert set(left.documents) == {"studio", "pose1"}
    scene, clip = left.read("studio")
    assert scene == {"frame": 3, "clip": "walk.bvh"}
    np.testing.assert_array_equal(clip.local_rot, synthetic_motion.local_rot)
    np.testing.assert_array_equal(clip.root_pos, synthetic_motion.root_pos)
    np.testing.assert_array_equal(clip.skeleton.offsets, synthetic_motion.skeleton.offsets)
    assert clip.fps == synthetic_motion.fps and left.read("pose1") == ({"keys": []}, None)
    left.discard()
    assert list(tmp_path.iterdir()) == []


def test_the_clip_is_dropped_when_the_document_no_longer_has_one(tmp_path, synthetic_motion):
    a = AutosaveSession(tmp_path)
    a.write("studio", {}, clip=synthetic_motion)
    assert a.path("studio", ".npz").is_file()
    a.write("studio", {})
    assert not a.path("studio", ".npz").exists()
    assert "edited_clip" not in json.loads(a.path("studio").read_text())
    a.close()


def test_a_killed_program_leaves_its_session_for_the_next_start(tmp_path):
    code = (
        "import os, signal, sys; from engine.autosave import AutosaveSession; "
        "AutosaveSession(sys.argv[1]).write('studio', {'frame': 7}); os.kill(os.getpid(), signal.SIGKILL)"
    )
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([os.getcwd(), os.environ.get("PYTHONPATH", "")])}
    proc = subprocess.run([sys.executable, "-c", code, str(tmp_path)], env=env, timeout=120)
    assert proc.returncode == -signal.SIGKILL
    [left] = left_sessions(tmp_path)
    assert left.read("studio")[0] == {"frame": 7}


def test_a_malformed_autosave_names_the_file_and_field(tmp_path):
    a = AutosaveSession(tmp_path)
    path = a.write("studio", {})
    a.abandon()
    path.write_text(json.dumps({"format": "dragposer-autosave", "version": 1, "scene": []}))
    [left] = left_sessions(tmp_path)
    with pytest.raises(UserError, match=f"{path}: field 'scene' must be an object"):
        left.read("studio")
    bad = tmp_path / "clip.npz"
    bad.write_bytes(b"not a zip")
    with pytest.raises(UserError, match=f"{bad}: cannot read the autosaved clip"):
        load_clip(bad)


def test_the_lock_of_a_dead_program_with_nothing_unsaved_is_cleared(tmp_path):
    a, b = AutosaveSession(tmp_path), AutosaveSession(tmp_path)
    a.abandon()  # died with no document
    assert left_sessions(tmp_path) == []
    assert [p.name for p in tmp_path.iterdir()] == [f"autosave-{b.id}.lock"]  # the running one's stays
    b.close()
