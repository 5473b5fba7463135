"""The pose window's autosave document: everything the model holds, written as JSON and
read back bit for bit, as one undo step (engine/authoring/recovery.py)."""

from __future__ import annotations

import json

import numpy as np
import pytest

from engine import skeleton as sk
from engine.authoring.pose_mode import PoseMode
from engine.authoring.recovery import document, recover
from engine.authoring.session import AuthoringSession
from engine.authoring.state import differences
from engine.errors import UserError
from tests.engine.authoring.test_session import Clock


def same(a, b) -> bool:
    """Equal in every part but the constraint objects' identity (compared by value)."""
    d = differences(a, b)
    planted = [j for j, _ in a.planted] == [j for j, _ in b.planted] and all(
        np.array_equal(p, q) for (_, p), (_, q) in zip(a.planted, b.planted)
    )
    constraints = [c.to_dict() for c in a.constraints] == [c.to_dict() for c in b.constraints]
    return not (d.joints or d.keys or d.pose or d.animation) and planted and constraints


def edited(vae) -> AuthoringSession:
    s = AuthoringSession(PoseMode(vae, 1.6), clock=Clock(1.0))
    s.drag_joint("lwrist", s.pose.positions[sk.JOINT_INDEX["lwrist"]] + [0.05, -0.1, 0.15])
    s.turn_joint("rwrist", np.array([0.9, 0.1, 0.3, -0.2]) / np.linalg.norm([0.9, 0.1, 0.3, -0.2]))
    s.add_key(0)
    s.set_length(90)
    s.move_body(np.array([0.2, 0.1, 0.0]))
    s.turn_body(30.0)
    s.add_key(40)
    s.add_constraint("floor")
    s.edit_target("lwrist", weight=3.0)
    s.drag_joint("rankle", s.pose.positions[sk.JOINT_INDEX["rankle"]] + [0.0, 0.1, 0.05])  # not keyed
    return s


def test_the_document_gives_back_the_exact_state_as_one_unsaved_step(vae):
    s = edited(vae)
    doc = json.loads(json.dumps(document(s), allow_nan=False))  # what the autosave file holds
    back = AuthoringSession(PoseMode(vae, 1.75), clock=Clock(1.0))
    recover(back, doc, "a.json")
    assert same(s.state(), back.state()) and s.state().planted
    assert back.frame == s.frame and back.mode.character.height == pytest.approx(1.6)
    assert back.scene.animation.frames == 90 and [k.frame for k in back.keys] == [0, 40]
    assert back.dirty and back.history.undo_text() == "recovered session"
    back.undo()  # the scene as a document, without the pose being made
    assert [k.frame for k in back.keys] == [0, 40] and "rankle" not in back.mode.targets


def test_an_edit_of_an_in_between_is_recovered_as_not_keyed(vae):
    s = AuthoringSession(PoseMode(vae, 1.6), clock=Clock(1.0))
    s.add_key(0)
    s.drag_joint("lwrist", s.pose.positions[sk.JOINT_INDEX["lwrist"]] + [0.05, -0.1, 0.15])
    s.add_key(20)
    s.go_to(10)
    assert not s.unkeyed_edit()
    doc = json.loads(json.dumps(document(s)))
    back = AuthoringSession(PoseMode(vae, 1.6), clock=Clock(1.0))
    recover(back, doc, "a.json")
    assert back.frame == 10 and not back.unkeyed_edit(), "the in-between as entered"
    s.drag_joint("rwrist", s.pose.positions[sk.JOINT_INDEX["rwrist"]] + [0.0, 0.0, 0.1])
    assert s.unkeyed_edit()
    doc = json.loads(json.dumps(document(s)))
    back = AuthoringSession(PoseMode(vae, 1.6), clock=Clock(1.0))
    recover(back, doc, "a.json")
    assert back.frame == 10 and back.unkeyed_edit() and same(s.state(), back.state())
    assert back.go_to(12) == 10, "leaving drops it, one undo step"
    back.undo()
    assert back.frame == 10 and back.unkeyed_edit() and same(s.state(), back.state())


def test_a_broken_document_names_the_file_and_field_and_changes_nothing(vae):
    s = edited(vae)
    doc = json.loads(json.dumps(document(s)))
    doc["recovery"]["pose"]["local_rot"] = [[1, 0, 0, 0]]
    back = AuthoringSession(PoseMode(vae, 1.75), clock=Clock(1.0))
    before = back.state()
    with pytest.raises(UserError, match=r"a\.json: recovery: pose: local_rot must be 22x4 finite numbers"):
        recover(back, doc, "a.json")
    assert same(before, back.state()) and not back.dirty
    del doc["recovery"]
    with pytest.raises(UserError, match="a.json: field 'recovery' must be an object"):
        recover(back, doc, "a.json")
