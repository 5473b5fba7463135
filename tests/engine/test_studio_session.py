"""Session: the Qt-free studio model fires typed events and forwards commands."""

from __future__ import annotations

import json

import numpy as np
import pytest

from engine.editing.constraint_list import PIN_PREFIX, ConstraintList
from engine.errors import UserError
from engine.sensors import Sensor
from engine.studio import commands as c
from engine.studio import events as ev
from engine.studio.session import Session


@pytest.fixture
def session(synthetic_motion):
    s = Session()
    s.set_motion(synthetic_motion)
    return s


def test_changes_fire_typed_events_and_become_commands(session):
    seen, commands = [], []
    session.events.sensors.connect(seen.append)
    session.events.frame.connect(seen.append)
    session.events.settings.connect(seen.append)
    session.attach(commands.append)
    commands.clear()
    joint = next(iter(session.sensors))
    old = session.sensors[joint]
    session.sensors.edit(joint, enabled=False)
    session.seek(10)
    session.set_setting("iterations", 5)
    assert isinstance(seen[0], ev.SensorsChanged) and seen[0].joint == joint
    assert seen[0].old == old and seen[0].new.enabled is False
    assert seen[1] == 10
    assert isinstance(seen[2], ev.SettingsChanged) and seen[2].changed == {"iterations": 5}
    assert isinstance(commands[0], c.SetSensors) and not commands[0].sensors[0].enabled
    assert commands[1] == c.Seek(10) and commands[2] == c.SetSettings({"iterations": 5})
    session.events.frame.disconnect(seen.append)
    session.seek(3)
    assert 3 not in seen


def test_an_unchanged_sensor_edit_fires_nothing(session):
    seen = []
    session.events.sensors.connect(seen.append)
    joint = next(iter(session.sensors))
    session.sensors.edit(joint, enabled=True)
    assert seen == []


def test_preset_and_bad_sensor_edits(session):
    name, sensors = list(session.sensors.presets().items())[-1]
    seen = []
    session.events.sensors.connect(seen.append)
    before = tuple(session.sensors.values())
    session.sensors.set_preset(name)
    assert tuple(session.sensors.values()) == sensors
    assert seen[-1].joint is None and seen[-1].old_set == before and seen[-1].preset == name
    with pytest.raises(UserError, match="unknown sensor preset"):
        session.sensors.set_preset("no such preset")
    with pytest.raises(UserError, match="dof"):
        session.sensors.edit(sensors[0].joint, dof=4)
    with pytest.raises(UserError, match="unknown field"):
        session.sensors.edit(sensors[0].joint, colour="red")


def test_drag_target_sets_offset_from_the_tracked_position(session):
    joint = next(iter(session.sensors))
    base = session.tracked_position(joint, session.frame)
    session.drag_target(joint, base + [0.1, 0.0, -0.2])
    assert np.allclose(session.sensors[joint].offset, [0.1, 0.0, -0.2])
    session.simulate_failure(joint, 30)
    assert session.sensors[joint].lost_at(10) and not session.sensors[joint].lost_at(30)
    session.sensors.reset_offsets()
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
    session.sensors.edit(joint, dof=3, weight=0.5, offset=(0.0, 0.1, 0.0))
    session.set_setting("lr", 0.05)
    session.constraints.add("distance", joint_a="lwrist", joint_b="rwrist", distance=0.4)
    scene = json.loads(json.dumps(session.to_scene()))
    other = Session()
    other.set_motion(session.motion)
    other.apply_scene(scene)
    assert other.sensors == session.sensors
    assert other.settings["lr"] == 0.05
    assert [x.to_dict() for x in other.constraints] == [x.to_dict() for x in session.constraints]


def test_studio_scenes_are_optimizer_scenes(session, tmp_path):
    """One scene format and one parser (engine.scene): the CLI reads what the studio saves,
    and the studio refuses what engine.scene refuses."""
    from engine.scene import load_scene

    session.set_setting("lr", 0.05)
    session.constraints.add("distance", joint_a="lwrist", joint_b="rwrist", distance=0.4)
    path = tmp_path / "studio.json"
    path.write_text(json.dumps(session.to_scene()))
    constraints, settings = load_scene(path)
    assert settings.lr == 0.05 and [c.to_dict() for c in constraints] == [c.to_dict() for c in session.constraints]
    for bad, message in (({"lr": 0}, r"s.json: settings: .*lr"), ({"colour": 1}, r"settings: unknown field 'colour'")):
        scene = {**session.to_scene(), "settings": bad}
        with pytest.raises(UserError, match=message):
            session.apply_scene(scene, "s.json")
    assert session.settings["lr"] == 0.05
    scene = session.to_scene()
    scene["constraints"] = scene["constraints"] * 2
    with pytest.raises(UserError, match="duplicate name"):
        session.apply_scene(scene, "s.json")


def test_a_bad_scene_names_the_entry_and_changes_nothing(session):
    scene = session.to_scene()
    scene["sensors"][1]["dof"] = 5
    before = dict(session.sensors)
    with pytest.raises(UserError, match=r"my.json: sensors\[1\].*dof"):
        session.apply_scene(scene, "my.json")
    assert session.sensors == before


def test_sensor_text_accepts_presets_and_joint_lists(session):
    session.sensors.set_text("root,lwrist:3")
    assert list(session.sensors) == ["root", "lwrist"] and session.sensors["lwrist"].dof == 3
    assert isinstance(session.sensors["root"], Sensor) and session.preset == ""
    with pytest.raises(UserError):
        session.sensors.set_text("root,nose")


def test_catalog_offers_user_kinds_with_their_fields_but_not_internal_ones():
    catalog = ConstraintList.catalog()
    assert {"pin", "look_at", "distance", "bounds", "floor", "balance", "end_effector"} <= set(catalog)
    assert "sensor" not in catalog and "temporal_prior" not in catalog
    assert catalog["pin"].field("joint").tag == "joint" and catalog["pin"].field("position").tag == "vec3"
    mode = catalog["balance"].field("mode")
    assert mode.tag == "choice" and "com_over_feet" in mode.choices


def test_constraints_are_added_by_kind_edited_by_replacement_and_removed(session):
    seen, commands = [], []
    session.events.constraints.connect(seen.append)
    session.attach(commands.append)
    name = session.constraints.add("distance", joint_a="lwrist", joint_b="rwrist", distance=0.3)
    assert name == "distance" and seen[-1].action == "added" and seen[-1].index == 0
    first = session.constraints.named(name)
    assert commands[-1] == c.SetConstraints((first,))  # the session's own object, no copy
    session.constraints.edit(name, distance=0.5, weight=2.0)
    second = session.constraints.named(name)
    assert second is not first and first.distance == 0.3, "published objects are never edited"
    assert second.distance == 0.5 and seen[-1].old is first and seen[-1].new is second
    assert session.constraints.add("distance") == "distance1"
    with pytest.raises(UserError, match="unknown constraint kind 'sensor'"):
        session.constraints.add("sensor")
    with pytest.raises(UserError, match="no field 'colour'"):
        session.constraints.edit(name, colour="red")
    with pytest.raises(UserError, match="weight"):
        session.constraints.edit(name, weight=-1.0)
    session.constraints.remove(name)
    assert seen[-1].action == "removed" and seen[-1].old is second
    session.constraints.insert(seen[-1].old, seen[-1].index)  # what an undo does
    assert session.constraints[0] is second


def test_pin_creates_then_moves_one_pin_per_joint(session):
    name = session.constraints.pin("lelbow", np.array([0.1, 0.2, 1.0]))
    assert name == PIN_PREFIX + "lelbow"
    session.constraints.pin("lelbow", np.array([0.3, 0.2, 1.0]))
    (pin,) = session.constraints
    assert pin.kind == "pin" and pin.joint == "lelbow" and np.allclose(pin.position, [0.3, 0.2, 1.0])
    session.constraints.unpin("lelbow")
    assert list(session.constraints) == []


def test_the_sub_models_fire_their_own_events_which_the_session_sends_and_relays(session):
    """``session.constraints`` and ``session.sensors`` announce each edit on their own
    ``events.changed``; the session sends the new set to the engine and re-emits the
    same payload on its own group."""
    own, relayed, commands = [], [], []
    session.constraints.events.changed.connect(own.append)
    session.events.constraints.connect(relayed.append)
    session.attach(commands.append)
    commands.clear()
    name = session.constraints.add("floor")
    assert own == relayed and own[-1].action == "added" and own[-1].name == name and own[-1].new.kind == "floor"
    assert commands == [c.SetConstraints((session.constraints.named(name),))]
    sensors_seen = []
    session.sensors.events.changed.connect(sensors_seen.append)
    joint = next(iter(session.sensors))
    session.sensors.edit(joint, weight=3.0)
    e = sensors_seen[-1]
    assert (e.joint, e.old.weight, e.new.weight) == (joint, 1.0, 3.0) and isinstance(commands[-1], c.SetSensors)
    session.sensors.remove(joint)
    assert sensors_seen[-1].old.joint == joint and sensors_seen[-1].new is None and session.preset == ""


def test_a_constraint_list_edits_a_list_it_is_given_in_place():
    """The pose window's constraints are one list shared with its pose mode and scene."""
    shared: list = []
    seen = []
    constraints = ConstraintList(shared)
    constraints.events.changed.connect(seen.append)
    constraints.add("floor")
    constraints.set_all(list(constraints) + [constraints.named("floor").__class__(name="other")])
    assert [c.name for c in shared] == ["floor", "other"] and seen[-1].action == "replaced"
    assert seen[-1].old_list[0] is shared[0] and len(seen[-1].old_list) == 1
    with pytest.raises(UserError, match="no constraint named 'nope'"):
        constraints.named("nope")


def test_playback_state_and_pace_go_through_the_session(session):
    seen, commands = [], []
    session.events.playback.connect(seen.append)
    session.attach(commands.append)
    assert session.pace == "every_frame"
    session.set_playing(True)
    assert commands[-1] == c.Play(1.0, True, "every_frame") and seen[-1].playing
    session.set_playback(pace="real_time", speed=0.5)
    assert commands[-1] == c.Play(0.5, True, "real_time") and seen[-1].pace == "real_time"
    session.set_playing(False)
    assert commands[-1] == c.Pause() and not seen[-1].playing
    with pytest.raises(UserError, match="playback pace"):
        session.set_playback(pace="fast")


def test_method_changes_carry_the_previous_method(session):
    seen = []
    session.events.method.connect(seen.append)
    session.set_method("dragposer", ghosts=("ik", "dragposer"))
    assert seen[-1] == ev.MethodChanged("dragposer", ("ik",), "ik", ())


def _pose_window_scene() -> dict:
    """A scene as the pose window saves it: character, animation, keys, a constraint, no sensors."""
    from engine.authoring.document import AuthoringScene, authoring_to_dict
    from engine.authoring.keys import Animation, Key
    from engine.authoring.targets import JointTarget
    from engine.constraints.base import from_dict

    floor = from_dict({"kind": "floor", "name": "floor"})
    keys = [Key(0, {"lwrist": JointTarget("lwrist", [0.3, 0.0, 1.2])}), Key(20)]
    return authoring_to_dict(AuthoringScene([floor], animation=Animation(30.0, 40), keys=keys, height=1.8))


def test_a_pose_window_scene_keeps_the_sensors_and_says_what_it_replaced(session):
    session.seek(17)
    before, preset = dict(session.sensors), session.preset
    assert before
    said = session.apply_scene(json.loads(json.dumps(_pose_window_scene())), "pose.json")
    assert session.sensors == before and session.preset == preset and session.frame == 17
    assert [x.name for x in session.constraints] == ["floor"]
    n = len(_pose_window_scene()["settings"])
    assert said == (
        f"replaced the constraints (1) and the optimizer settings ({n}); kept the sensors and preset (the scene has none); "
        "its 2 keys are for the pose window and bake"
    )
    scene = {**session.to_scene(), "sensors": []}
    said = session.apply_scene(scene)
    assert (
        said == f"replaced the constraints (1), the optimizer settings ({len(scene['settings'])}) and the sensors (0)"
    )
    assert session.sensors == {}


def test_the_studio_refuses_a_scene_exactly_as_bake_does(session, tmp_path):
    from engine.authoring.document import load_authoring

    doc = _pose_window_scene()
    doc["animation"]["fps"] = "fast"
    path = tmp_path / "fast.json"
    path.write_text(json.dumps(doc))
    with pytest.raises(UserError) as by_bake:
        load_authoring(path)
    before = dict(session.sensors)
    with pytest.raises(UserError) as by_studio:
        session.apply_scene(doc, str(path))
    assert str(by_studio.value) == str(by_bake.value)
    assert "animation: field 'fps' must be a number" in str(by_bake.value)
    assert session.sensors == before


def test_replace_settings_leaves_unset_what_it_does_not_give_and_tells_the_engine(session):
    from engine.studio.method_set import MethodSet

    commands = []
    session.attach(commands.append)
    session.set_setting("smooth_weight", 2.0)
    kept = {k: v for k, v in session.settings.items() if k != "smooth_weight"}
    session.replace_settings(kept)
    assert "smooth_weight" not in session.settings and dict(session.settings) == kept
    last = commands[-1]
    assert isinstance(last, c.SetSettings) and last.replace and dict(last.values) == kept
    methods = MethodSet.__new__(MethodSet)  # the engine side: only its settings are looked at
    methods.settings = session.settings | {"smooth_weight": 2.0}
    methods.configure = lambda *a, **k: None
    methods.set_settings(last.values, last.replace)
    assert dict(methods.settings) == kept
