"""``bake``: the example scene as written, keys on their targets, smooth grounded in-betweens."""

from __future__ import annotations

import json

import numpy as np
import pytest

from engine import skeleton as sk
from engine.authoring.bake import bake, interpolated_targets, one_key_targets
from engine.authoring.document import load_authoring
from engine.authoring.export import bake_to_file
from engine.authoring.keys import Key
from engine.authoring.targets import JointTarget
from engine.cli.main import main
from engine.motion.bvh import load_bvh

LW = sk.JOINT_INDEX["lwrist"]


@pytest.fixture(scope="module")
def baked(vae, tmp_path_factory):
    """The example baked the way the studio exports it: (scene, Baked, the BVH path)."""
    from tests.engine.authoring.conftest import EXAMPLE

    folder = tmp_path_factory.mktemp("bake")
    path = folder / "example.json"
    path.write_text(EXAMPLE)
    scene = load_authoring(path)
    return scene, bake_to_file(scene, vae, folder / "studio.bvh"), folder / "studio.bvh"


def test_the_command_bakes_61_frames_at_30_fps_the_bytes_the_studio_exports(baked, example_scene, tmp_path, capsys):
    out = tmp_path / "out.bvh"
    assert main(["bake", str(example_scene), "--out", str(out), "--no-progress"]) == 0
    raw = load_bvh(out)
    assert raw.frames == 61 and raw.fps == pytest.approx(30.0, rel=1e-4)
    assert "61 frames at 30 fps" in capsys.readouterr().out
    assert out.read_bytes() == baked[2].read_bytes()


def test_bad_scenes_exit_2_naming_the_file_and_field(tmp_path, capsys):
    bad = tmp_path / "bad.json"
    bad.write_text(
        '{"format": "dragposer-scene", "version": 2, "animation": {"fps": 30, "frames": 10},'
        ' "keys": [{"frame": 12, "targets": {}}]}'
    )
    assert main(["bake", str(bad), "--out", str(tmp_path / "o.bvh"), "--no-progress"]) == 2
    err = capsys.readouterr().err
    assert "bad.json" in err and "keys[0]" in err and "frame" in err
    assert not (tmp_path / "o.bvh").exists()


def test_the_left_wrist_is_within_1_cm_of_each_key_target(baked):
    scene, result, _ = baked
    pos = result.motion.positions()
    for key in scene.keys:
        assert np.linalg.norm(pos[key.frame, LW] - key.targets["lwrist"].position) < 0.01, key.frame


def test_bone_lengths_are_constant_and_no_joint_is_below_the_floor(baked):
    _, result, _ = baked
    pos = result.motion.positions()
    bones = np.linalg.norm(pos[:, 1:] - pos[:, list(sk.PARENTS[1:])], axis=-1)
    assert np.ptp(bones, axis=0).max() < 1e-9
    assert np.allclose(bones[0], np.linalg.norm(result.motion.skeleton.offsets[1:], axis=-1), atol=1e-9)
    assert pos[..., 2].min() >= 0.0


def test_no_joint_moves_more_per_frame_than_twice_the_wrist_key_to_key_speed(baked):
    scene, result, _ = baked
    a, b = scene.keys
    bound = 2 * np.linalg.norm(b.targets["lwrist"].position - a.targets["lwrist"].position) / (b.frame - a.frame)
    step = np.linalg.norm(np.diff(result.motion.positions(), axis=0), axis=-1)
    assert step.max() <= bound, (step.max(), bound, sk.JOINT_NAMES[int(step.max(0).argmax())])
    assert step[:, LW].max() > 0.5 * bound  # the wrist really travels


def test_an_other_output_rate_keeps_the_duration(example_scene, vae):
    scene = load_authoring(example_scene)
    result = bake(scene, vae, fps=60)
    assert len(result.motion) == 121 and result.motion.fps == 60
    assert np.linalg.norm(result.motion.positions()[120, LW] - scene.keys[1].targets["lwrist"].position) < 0.01


def test_a_joint_targeted_by_both_keys_follows_an_eased_straight_path():
    a = Key(0, {"lwrist": JointTarget("lwrist", [0, 0, 1])})
    b = Key(10, {"lwrist": JointTarget("lwrist", [1, 0, 1]), "upperneck": JointTarget("upperneck", [0, 0, 2])})
    mid = interpolated_targets([a, b], [0.0, 10.0], 5.0, "cubic")
    assert [t.joint for t in mid] == ["lwrist"]  # the upperneck is keyed once only: free between
    assert np.allclose(mid[0].position, [0.5, 0, 1])
    early = interpolated_targets([a, b], [0.0, 10.0], 1.0, "cubic")[0].position[0]
    late = interpolated_targets([a, b], [0.0, 10.0], 1.0, "linear")[0].position[0]
    assert 0 < early < late == pytest.approx(0.1)  # cubic eases out of the key
    # what the pose window's Targets list says of the upperneck between them
    assert one_key_targets([a, b], 5.0) == {"upperneck": 10}
    assert one_key_targets([a, b], 10.0) == {} == one_key_targets([a, b], 12.0) == one_key_targets([a, b], 0.0)


def test_the_command_bakes_to_gltf_with_the_bvh_s_joints(baked, example_scene, tmp_path):
    from tests.engine.gltf_reading import Y_UP_TO_Z_UP, bvh_world_positions, read_gltf, validate, validator_command

    out = tmp_path / "out.glb"
    assert main(["bake", str(example_scene), "--out", str(out), "--no-progress"]) == 0
    raw = load_bvh(baked[2])
    read = read_gltf(out)
    got = read.world_positions([read.node_index(n) for n in raw.names], raw.frames) @ Y_UP_TO_Z_UP.T
    assert np.abs(got - bvh_world_positions(raw)).max() < 1e-5
    assert read.doc.meshes
    if validator_command() is not None:
        assert [(r["errors"], r["warnings"]) for r in validate([out])] == [(0, 0)]


def test_bake_refuses_a_misspelt_key_naming_it_and_exits_non_zero(tmp_path, capsys):
    """``keys`` misspelt ``keyz`` read as absent would bake the animation without its keys and exit 0."""
    scene = tmp_path / "s.json"
    scene.write_text(
        json.dumps(
            {
                "format": "dragposer-scene",
                "version": 2,
                "animation": {"frames": 61},
                "keyz": [{"frame": 0, "targets": {"lwrist": [0.3, -0.2, 1.2]}}],
            }
        )
    )
    out = tmp_path / "o.bvh"
    assert main(["bake", str(scene), "--out", str(out), "--no-progress"]) == 2
    err = capsys.readouterr().err
    assert "s.json" in err and "unknown field 'keyz' (did you mean 'keys'?)" in err, err
    assert not out.exists()


@pytest.mark.parametrize(
    ("constraint", "said"),
    [
        (
            {"kindd": "pin", "joint": "lwrist"},
            "constraints[0]: no field 'kind'; unknown field 'kindd' (did you mean 'kind'?)",
        ),
        ({"kind": "pinn", "joint": "lwrist"}, "constraints[0]: unknown constraint kind 'pinn' (did you mean 'pin'?)"),
    ],
)
def test_bake_names_a_misspelt_constraint_kind_and_the_nearest_known_one(tmp_path, capsys, constraint, said):
    """A constraint's ``kind`` key or value misspelt is named with the one meant, as any other key is."""
    scene = tmp_path / "s.json"
    scene.write_text(
        json.dumps(
            {"format": "dragposer-scene", "version": 2, "animation": {"frames": 61}, "constraints": [constraint]}
        )
    )
    out = tmp_path / "o.bvh"
    assert main(["bake", str(scene), "--out", str(out), "--no-progress"]) == 2
    err = capsys.readouterr().err
    assert said in err, err
    assert not out.exists()
