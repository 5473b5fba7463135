"""Scene format version 2: round trips, version-1 scenes, errors naming the field."""

from __future__ import annotations

import json

import numpy as np
import pytest

from engine.authoring.document import AuthoringScene, authoring_from_dict, load_authoring, save_authoring
from engine.authoring.keys import Animation, Key
from engine.authoring.targets import JointTarget
from engine.constraints import FloorConstraint, PinConstraint
from engine.errors import UserError
from engine.scene import save_scene, scene_from_dict

V1 = {
    "format": "dragposer-scene",
    "version": 1,
    "settings": {"mode": "offline"},
    "constraints": [
        {
            "kind": "pin",
            "name": "p",
            "weight": 2.0,
            "enabled": True,
            "joint": "lankle",
            "position": [0, 0, 0.1],
            "follow_previous": False,
            "tolerance": 0.01,
        }
    ],
}


def test_a_version_1_scene_still_loads_everywhere(tmp_path):
    path = tmp_path / "v1.json"
    path.write_text(json.dumps(V1))
    scene = load_authoring(path)
    assert scene.version == 1 and scene.keys == [] and scene.settings.mode == "offline"
    assert scene.constraints[0].kind == "pin" and scene.constraints[0].frames is None
    constraints, settings = scene_from_dict(V1)
    assert constraints[0].to_dict() == scene.constraints[0].to_dict()


def test_a_scene_without_authoring_content_is_still_written_as_version_1(tmp_path):
    save_scene(tmp_path / "s.json", [PinConstraint(name="p")])
    assert json.loads((tmp_path / "s.json").read_text())["version"] == 1
    save_scene(tmp_path / "r.json", [PinConstraint(name="p", frames=(1, 4))])
    assert json.loads((tmp_path / "r.json").read_text())["version"] == 2


def test_the_example_reads_as_written(example_scene):
    scene = load_authoring(example_scene)
    assert (scene.animation.fps, scene.animation.frames, scene.animation.interpolation) == (30.0, 61, "cubic")
    assert [k.frame for k in scene.keys] == [0, 60]
    assert np.allclose(scene.keys[1].targets["lwrist"].position, [0.45, -0.10, 1.75])
    assert scene.constraints[0].kind == "floor"


def test_an_authoring_scene_round_trips(tmp_path):
    scene = AuthoringScene(
        [FloorConstraint(name="floor", frames=(3, 9), blend_in=2)],
        animation=Animation(24.0, 40, "spherical"),
        keys=[
            Key(
                30,
                {"rwrist": JointTarget("rwrist", [0.1, 0.2, 1.3], [0, 0, 0, 1], 4.0, False)},
                np.arange(24, dtype=np.float32),
                np.array([0.5, -1.0]),
                90.0,
            ),
            Key(2, {"lankle": JointTarget("lankle", [0, 0, 0.1])}),
        ],
        height=1.6,
    )
    save_authoring(tmp_path / "a.json", scene)
    back = load_authoring(tmp_path / "a.json")
    assert [k.frame for k in back.keys] == [2, 30] and back.height == 1.6
    k = back.keys[1]
    assert np.allclose(k.latent, np.arange(24)) and np.allclose(k.root, [0.5, -1.0]) and k.heading == 90.0
    t = k.targets["rwrist"]
    assert np.allclose(t.rotation, [0, 0, 0, 1]) and t.weight == 4.0 and not t.enabled
    assert back.constraints[0].frames == (3, 9) and back.animation.interpolation == "spherical"
    save_authoring(tmp_path / "b.json", back)
    save_authoring(tmp_path / "c.json", load_authoring(tmp_path / "b.json"))
    assert (tmp_path / "c.json").read_text() == (tmp_path / "b.json").read_text()
    assert json.loads((tmp_path / "b.json").read_text())["keys"][0]["targets"]["lankle"] == [0, 0, 0.1]


def _doc(**extra):
    return {"format": "dragposer-scene", "version": 2, "animation": {"fps": 30, "frames": 10}, **extra}


@pytest.mark.parametrize(
    "doc, words",
    [
        ({**V1, "keys": []}, ["keys", "version"]),
        (_doc(version=3), ["version"]),
        (_doc(keys=[{"frame": 10}]), ["keys[0]", "frame"]),
        (_doc(keys=[{"frame": 1}, {"frame": 1}]), ["keys", "frame(s) 1"]),
        (_doc(keys=[{"frame": 1, "targets": {"tail": [0, 0, 1]}}]), ["keys[0]", "tail"]),
        (_doc(keys=[{"frame": 1, "targets": {"lwrist": [0, 1]}}]), ["keys[0]", "lwrist", "position"]),
        (_doc(keys=[{"frame": 1, "targets": {"lwrist": {"position": [0, 0, 1], "weight": 11}}}]), ["weight"]),
        (_doc(keys=[{"frame": 1, "latent": ["a"]}]), ["keys[0]", "latent"]),
        (_doc(keys=[{"frame": 1, "spin": 2}]), ["keys[0]", "spin"]),
        (_doc(animation={"fps": 0, "frames": 3}), ["animation", "fps"]),
        (_doc(animation={"frames": 2.5}), ["animation", "frames"]),
        (_doc(animation={"interpolation": "bezier"}), ["interpolation"]),
        (_doc(character={"height": 7}), ["character", "height"]),
    ],
)
def test_bad_fields_are_named(doc, words):
    with pytest.raises(UserError) as err:
        authoring_from_dict(doc, "s.json")
    msg = str(err.value)
    assert msg.startswith("s.json") and all(w in msg for w in words), msg


@pytest.mark.parametrize(
    "doc, unknown, nearest",
    [
        (_doc(keyz=[{"frame": 1}]), "keyz", "keys"),
        (_doc(animaton={"frames": 3}), "animaton", "animation"),
        ({**V1, "setings": {}}, "setings", "settings"),
        (_doc(settings={"iteration": 3}), "iteration", "iterations"),
        (_doc(animation={"fps": 30, "frame": 10}), "frame", "frames"),
        (_doc(keys=[{"frame": 1, "heading_deg": 3}]), "heading_deg", "heading"),
        (_doc(keys=[{"frame": 1, "targets": {"lwrist": {"positon": [0, 0, 1]}}}]), "positon", "position"),
        (_doc(constraints=[{**V1["constraints"][0], "frame": [1, 2]}]), "frame", "frames"),
    ],
)
def test_an_unknown_key_is_named_with_the_nearest_known_one(doc, unknown, nearest):
    """A misspelt key read as absent changes the result silently (``keyz``: a bake with no
    keys); every level of the scene refuses it and suggests the key meant."""
    with pytest.raises(UserError) as err:
        authoring_from_dict(doc, "s.json")
    msg = str(err.value)
    assert msg.startswith("s.json") and f"unknown field '{unknown}' (did you mean '{nearest}'?)" in msg, msg


def test_an_unknown_key_with_no_near_one_lists_the_known_ones():
    with pytest.raises(UserError, match=r"s.json: unknown field 'zzzzzz'; known: animation, character, clip"):
        authoring_from_dict(_doc(zzzzzz=1), "s.json")


def test_the_studio_scene_keys_are_known_to_the_one_validator():
    """The studio writes its own keys (clip, sensors...); they load everywhere."""
    from engine.studio.session import Session

    doc = Session(method="ik").to_scene()
    authoring_from_dict(doc, "s.json")
    scene_from_dict(doc, "s.json")
