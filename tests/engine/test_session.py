"""Session: the Qt-free studio model announces changes and forwards them as commands."""

from __future__ import annotations

import json

import numpy as np
import pytest

from engine import worker as w
from engine.errors import UserError
from engine.session import Session, sensor_presets


@pytest.fixture
def session(synthetic_motion):
    s = Session()
    s.set_motion(synthetic_motion)
    return s


def test_changes_are_announced_and_forwarded(session):
    events, commands = [], []
    unsubscribe = session.subscribe(lambda e, d: events.append(e))
    session.sink = commands.append
    joint = next(iter(session.sensors))
    session.update_sensor(joint, enabled=False)
    session.seek(10)
    session.set_setting("iterations", 5)
    assert events == ["sensors", "frame", "settings"]
    assert isinstance(commands[0], w.SetSensors) and not commands[0].sensors[0].enabled
    assert commands[1] == w.Seek(10) and commands[2] == w.SetSettings({"iterations": 5})
    unsubscribe()
    session.seek(3)
    assert len(events) == 3


def test_preset_and_bad_sensor_edits(session):
    name, joints = list(sensor_presets().items())[-1]
    session.set_preset(name)
    assert tuple(session.sensors) == joints
    with pytest.raises(UserError):
        session.set_preset("no such preset")
    with pytest.raises(UserError):
        session.update_sensor(joints[0], dof=4)


def test_drag_target_sets_offset_from_the_tracked_position(session):
    joint = next(iter(session.sensors))
    base = session.tracked_position(joint, session.frame)
    session.drag_target(joint, base + [0.1, 0.0, -0.2])
    assert np.allclose(session.sensors[joint].offset, [0.1, 0.0, -0.2])
    session.simulate_failure(joint, 30)
    assert session.sensors[joint].lost_at(10) and not session.sensors[joint].lost_at(30)
    session.reset_offsets()
    assert session.sensors[joint].offset == (0.0, 0.0, 0.0) and not session.sensors[joint].failures


def test_open_bad_file_leaves_session_unchanged(session, tmp_path):
    bad = tmp_path / "bad.bvh"
    bad.write_text("HIERARCHY\nROOT broken {\n")
    before = session.motion
    with pytest.raises(UserError, match="bad.bvh"):
        session.open(bad)
    with pytest.raises(UserError, match="no such file"):
        session.open(tmp_path / "missing.bvh")
    assert session.motion is before


def test_scene_round_trip(session):
    joint = next(iter(session.sensors))
    session.update_sensor(joint, dof=3, weight=0.5, offset=(0.0, 0.1, 0.0))
    session.set_setting("lr", 0.05)
    scene = json.loads(json.dumps(session.to_scene()))
    other = Session()
    other.set_motion(session.motion)
    other.apply_scene(scene)
    assert other.sensors == session.sensors
    assert other.settings["lr"] == 0.05


def test_sensor_text_accepts_presets_and_joint_lists(session):
    session.set_sensor_text("root,lwrist:3")
    assert list(session.sensors) == ["root", "lwrist"] and session.sensors["lwrist"].dof == 3
    with pytest.raises(UserError):
        session.set_sensor_text("root,nose")
