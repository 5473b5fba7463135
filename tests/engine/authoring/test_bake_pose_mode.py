"""One natural-pose machinery: a baked key is posed by pose mode (planted feet, balance,
crouch, the scene's ``pose_options``), so a one-key bake is the pose the pose window gives
for the same targets (engine/authoring/bake.py, ``PoseMode.pose_key``; the task scenes of
``assets/scenes/pose_tasks`` that ``bench --pose-tasks`` bakes)."""

from __future__ import annotations

import dataclasses
import json

import numpy as np
import pytest

from engine import skeleton as sk
from engine.authoring import pose_tasks as T
from engine.authoring.bake import bake
from engine.authoring.document import authoring_from_dict, authoring_to_dict, load_authoring
from engine.authoring.keys import Key
from engine.authoring.pose_metrics import check_pose
from engine.authoring.pose_mode import PoseMode
from engine.authoring.pose_options import RANGE, PoseOptions
from engine.errors import UserError

J = sk.JOINT_INDEX
TASK = {t.name: t for t in T.TASKS}


def posed(vae, task, options: PoseOptions | None = None) -> PoseMode:
    """``task`` done in pose mode as the pose window does it: each goal dragged in turn."""
    mode = PoseMode(vae, options=options)
    offsets = mode.character.skeleton.offsets
    for goal in T.resolve_goals(task, mode.pose, offsets, mode.heading):
        T.drag(mode, goal, offsets)
    return mode


def baked_frame(vae, scene) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Local rotations, root and joint positions of a one-key scene's baked frame."""
    m = bake(scene, vae).motion
    assert len(m) == 1
    return m.local_rot[0], m.root_pos[0], m.positions()[0]


@pytest.mark.parametrize("name", T.TASK_NAMES)
def test_a_one_key_bake_is_the_pose_pose_mode_gives_for_the_same_targets(vae, name):
    mode = posed(vae, TASK[name])
    local, root, positions = baked_frame(vae, load_authoring(T.task_scene_path(TASK[name])))
    assert np.abs(positions - mode.pose.positions).max() < 1e-6
    assert np.abs(root - mode.pose.root_pos).max() < 1e-6
    assert np.abs(np.abs(np.sum(local * mode.pose.local_rot, axis=-1)) - 1.0).max() < 1e-9


def test_the_task_scenes_hold_the_tasks_goals(vae):
    """The files are what ``scripts/pose_task_scenes.py`` writes from the task table now."""
    for task in T.TASKS:
        want = T.task_scene(task, vae).keys[0].targets
        got = load_authoring(T.task_scene_path(task)).keys[0].targets
        assert list(got) == list(want), task.name
        for j, t in want.items():
            # the goals come from float32 decodes: another numpy or BLAS build moves them by
            # about 1e-7 m (1.3e-7 seen on a fresh install), far below any pose the task tells apart
            assert np.abs(got[j].position - t.position).max() < 1e-6, (task.name, j)
            assert (got[j].rotation is None) == (t.rotation is None)
            if t.rotation is not None:
                assert abs(abs(float(got[j].rotation @ t.rotation)) - 1.0) < 1e-12


def test_the_baked_squat_keeps_its_knees_off_the_floor_its_feet_down_and_its_balance(vae):
    scene = load_authoring(T.task_scene_path(TASK["squat"]))
    local, root, positions = baked_frame(vae, scene)
    assert abs(root[2] - scene.keys[0].targets["root"].position[2]) < 0.02  # the pelvis where it was put
    assert min(positions[J["lknee"], 2], positions[J["rknee"], 2]) > 0.25  # 0.30 m; kneeling: about 0.1-0.16
    check = check_pose(local, root, PoseMode(vae).character.skeleton.offsets)
    assert all(check.feet_down.values()) and check.balanced and check.violations == []


def test_the_scene_s_pose_options_reach_the_bake(vae):
    """A scene with ``pose_options`` bakes as pose mode posed with those options, not the defaults."""
    task = TASK["squat"]
    doc = json.loads(T.task_scene_path(task).read_text())
    doc["pose_options"] = {"plant_feet": False, "balance": False}
    scene = authoring_from_dict(doc, "squat.json")
    assert scene.pose_options == PoseOptions(plant_feet=False, balance=False)
    free = posed(vae, task, scene.pose_options)
    _, _, positions = baked_frame(vae, scene)
    assert np.abs(positions - free.pose.positions).max() < 1e-6
    assert np.abs(positions - posed(vae, task).pose.positions).max() > 0.01


def test_a_keyed_latent_bakes_as_the_pose_window_shows_that_key(vae):
    """A key the window stored (its latent, targets, place) bakes to the pose
    ``pose_key`` gives it, which is what the window shows on that key."""
    mode = posed(vae, TASK["squat"])
    key = Key(0, dict(mode.targets), mode.pose.latent.copy(), mode.pose.root_pos[:2].copy(), mode.heading)
    scene = authoring_from_dict({"format": "dragposer-scene", "version": 2, "animation": {"frames": 1}})
    scene.keys = [key]
    shown = PoseMode(vae).pose_key(key)
    _, _, positions = baked_frame(vae, scene)
    assert np.abs(positions - shown.positions).max() < 1e-6
    assert np.abs(positions - mode.pose.positions).max() < 0.05  # the keyed pose, up to where the feet were planted


def test_pose_options_round_trip_and_bad_ones_name_the_file_and_field():
    base = {"format": "dragposer-scene", "version": 2, "animation": {"frames": 1}}
    scene = authoring_from_dict(
        {**base, "pose_options": {"crouch_share": 0.3, "reach_rounds": 2.0, "keep_trunk": True}}, "s.json"
    )
    assert scene.pose_options == PoseOptions(crouch_share=0.3, reach_rounds=2, keep_trunk=True)
    doc = authoring_to_dict(scene)
    assert doc["pose_options"] == {"crouch_share": 0.3, "reach_rounds": 2, "keep_trunk": True}
    assert authoring_from_dict(json.loads(json.dumps(doc))).pose_options == scene.pose_options
    assert "pose_options" not in authoring_to_dict(authoring_from_dict(base))  # defaults are not written
    for bad, words in [
        ({"crouch_share": 2}, ["crouch_share", "0-1"]),
        ({"plant_feet": 1}, ["plant_feet", "true"]),
        ({"reach_rounds": 1.5}, ["reach_rounds", "whole"]),
        ({"nope": 1}, ["nope"]),
        ([1], ["object"]),
    ]:
        with pytest.raises(UserError) as err:
            authoring_from_dict({**base, "pose_options": bad}, "s.json")
        assert all(w in str(err.value) for w in ["s.json", "pose_options", *words]), str(err.value)
    with pytest.raises(UserError, match="version"):
        authoring_from_dict({"format": "dragposer-scene", "version": 1, "pose_options": {}}, "s.json")


def test_every_numeric_pose_option_declares_its_range():
    for f in dataclasses.fields(PoseOptions):
        if f.type not in ("bool", bool):
            lo, hi = f.metadata[RANGE]
            assert lo <= getattr(PoseOptions(), f.name) <= hi, f.name


def test_an_opened_scene_s_pose_options_pose_the_window_and_its_bake(vae):
    from engine.authoring.session import AuthoringSession

    session = AuthoringSession(PoseMode(vae))
    doc = json.loads(T.task_scene_path(TASK["squat"]).read_text())
    doc["pose_options"] = {"crouch_share": 0.25}
    session.open_scene(authoring_from_dict(doc, "squat.json"))
    assert session.mode.options.crouch_share == 0.25 and session.scene.pose_options is session.mode.options
    assert session.bake_job().scene.pose_options == PoseOptions(crouch_share=0.25)
    assert authoring_to_dict(session.scene)["pose_options"] == {"crouch_share": 0.25}
