"""glTF export (docs/export.md): the files read back with an independent reader
(tests/engine/gltf_reading.py) hold the BVH's joints, names, frames and rate, and the
Khronos validator finds nothing wrong with any of them."""

from __future__ import annotations

import numpy as np
import pytest

from engine import skeleton as sk
from engine.errors import UserError
from engine.kinematics import quaternion as Q
from engine.motion.bvh import load_bvh
from engine.motion.clip import Motion
from engine.motion.formats import GltfContents, motion_format, save_motion
from engine.tracking import simulate
from tests.engine.gltf_reading import (
    Y_UP_TO_Z_UP,
    bvh_world_positions,
    read_gltf,
    skinned_points,
    validate,
    validator_command,
    vtk_points_at,
)

TOL = 1e-5  # metres


def _motion(frames: int = 90, fps: float = 60.0, scale: float = 1.07, seed: int = 0) -> Motion:
    """Wide, fast turns of every joint (signs flip, angles pass 180 degrees) and a root
    that walks off several metres from the origin."""
    rng = np.random.default_rng(seed)
    t = np.arange(frames)[:, None] / fps
    axis = rng.normal(size=(sk.NUM_JOINTS, 3))
    axis /= np.linalg.norm(axis, axis=1, keepdims=True)
    angle = 2.5 * np.sin(2 * np.pi * (0.3 + rng.random(sk.NUM_JOINTS)) * t + rng.random(sk.NUM_JOINTS) * 6)
    rot = Q.from_axis_angle(np.broadcast_to(axis, (frames, sk.NUM_JOINTS, 3)), angle)
    root = np.c_[3.0 * t[:, 0], -1.5 * t[:, 0], 0.9 + 0.05 * np.sin(6 * t[:, 0])]
    return Motion(rot, root, sk.Skeleton.canonical(scale), fps, "synthetic")


def _joint_nodes(read, names: list[str]) -> list[int]:
    return [read.node_index(n) for n in names]


def _gltf_positions_z_up(path, names: list[str], frames: int) -> np.ndarray:
    read = read_gltf(path)
    return read.world_positions(_joint_nodes(read, names), frames) @ Y_UP_TO_Z_UP.T


@pytest.fixture(scope="module")
def written(tmp_path_factory):
    """Files of one clip: BVH, GLB with mesh, GLTF without, GLB with ghosts and trackers."""
    folder = tmp_path_factory.mktemp("gltf")
    motion = _motion()
    ghost = _motion(seed=1)
    tracking = simulate(motion, "6", faulty=0.05, seed=3)
    files = {"bvh": folder / "m.bvh", "glb": folder / "m.glb", "gltf": folder / "m.gltf", "full": folder / "full.glb"}
    save_motion(files["bvh"], motion)
    save_motion(files["glb"], motion)
    save_motion(files["gltf"], motion, contents=GltfContents(mesh=False))
    save_motion(files["full"], motion, contents=GltfContents(ghosts=(("ik", ghost),), tracking=tracking))
    return motion, ghost, tracking, files


def test_joint_positions_equal_the_bvh_on_every_frame(written):
    motion, _, _, files = written
    raw = load_bvh(files["bvh"])
    want = bvh_world_positions(raw)
    assert np.abs(want - motion.positions()).max() < TOL  # the BVH reader agrees with the engine's FK
    for key in ("glb", "gltf", "full"):
        got = _gltf_positions_z_up(files[key], list(raw.names), len(motion))
        assert got.shape == want.shape
        assert np.abs(got - want).max() < TOL, key


def test_frames_rate_names_rest_pose_and_bind_matrices(written):
    motion, _, _, files = written
    read = read_gltf(files["glb"])
    doc = read.doc
    skin = doc.skins[0]
    assert [doc.nodes[j].name for j in skin.joints] == list(sk.JOINT_NAMES)
    for node, path in ((skin.joints[0], "translation"), (skin.joints[5], "rotation")):
        times, values = read.channels()[(node, path)]
        assert len(times) == len(values) == len(motion)
        assert np.allclose(np.diff(times), 1 / motion.fps, atol=1e-6)
    assert doc.animations[0].extras == {"fps": 60.0, "frames": 90}
    # the rest pose is the BVH's: OFFSETs as translations, no rotation
    for j in range(1, sk.NUM_JOINTS):
        node = doc.nodes[skin.joints[j]]
        assert np.allclose(np.asarray(node.translation) @ Y_UP_TO_Z_UP.T, motion.skeleton.offsets[j], atol=1e-9)
        assert node.rotation in (None, [0, 0, 0, 1])
    # inverse bind matrices undo each joint's rest world transform
    ibm = read.accessor(skin.inverseBindMatrices).reshape(-1, 4, 4).transpose(0, 2, 1)
    rest_world = read.world_positions(list(skin.joints), 1)[0]  # the animation's first frame...
    nodes_rest = np.zeros((sk.NUM_JOINTS, 3))
    for j, p in enumerate(sk.PARENTS):
        nodes_rest[j] = np.asarray(doc.nodes[skin.joints[j]].translation) + (nodes_rest[p] if p >= 0 else 0)
    assert np.allclose(ibm[:, :3, 3], -nodes_rest, atol=1e-6) and np.allclose(ibm[:, :3, :3], np.eye(3))
    assert np.allclose(rest_world[0], nodes_rest[0], atol=1e-6)  # ...starts where the rest pose's root is


def test_the_mesh_is_skinned_with_smooth_weights_and_a_material(written):
    _, _, _, files = written
    read = read_gltf(files["glb"])
    doc = read.doc
    body = next(n for n in doc.nodes if n.mesh is not None)
    assert body.skin == 0 and body.translation is None and body.rotation is None
    prim = doc.meshes[body.mesh].primitives[0]
    weights = read.accessor(prim.attributes.WEIGHTS_0)
    joints = read.accessor(prim.attributes.JOINTS_0)
    assert np.allclose(weights.sum(1), 1.0, atol=1e-6)
    assert joints.max() < sk.NUM_JOINTS
    # smooth: many vertices share two joints half and half (the bends), none is torn off
    shared = (weights > 0.05).sum(1) >= 2
    assert shared.mean() > 0.15
    assert doc.materials[prim.material].pbrMetallicRoughness.baseColorFactor[3] == 1.0
    assert not read_gltf(files["gltf"]).doc.meshes  # --no-mesh: skeleton and animation only
    assert read_gltf(files["gltf"]).doc.skins


def test_ghosts_are_extra_characters_and_trackers_follow_their_targets(written):
    motion, ghost, tracking, files = written
    read = read_gltf(files["full"])
    doc = read.doc
    assert len(doc.skins) == 2 and len([m for m in doc.meshes if m.name.endswith("body")]) == 2
    names = [f"ik:{n}" for n in sk.JOINT_NAMES]
    got = read.world_positions(_joint_nodes(read, names), len(ghost)) @ Y_UP_TO_Z_UP.T
    assert np.abs(got - ghost.positions()).max() < TOL
    trackers = [read.node_index(f"tracker:{j}") for j in tracking.joints]
    pos = read.world_positions(trackers, len(motion)) @ Y_UP_TO_Z_UP.T
    assert np.abs(pos - tracking.positions).max() < TOL
    chans = read.channels()
    lost = [s for s in range(len(trackers)) if not tracking.connected[:, s].all()]
    assert lost, "the simulation should have lost a tracker"
    for s in lost:
        scale = chans[(trackers[s], "scale")][1]
        assert np.array_equal(scale[:, 0] > 0, tracking.connected[:, s])


def _check_vtk_skinning(path, frame: int, fps: float) -> None:
    """VTK's glTF reader, an outside importer, deforms every body at ``frame`` as linear
    blend skinning of the file's joints says (within 1e-5 m)."""
    read = read_gltf(path)
    bodies = [i for i, n in enumerate(read.doc.nodes) if n.skin is not None]
    vtk_meshes = [p for p in vtk_points_at(path, frame / fps) if len(p) > 100]
    assert len(vtk_meshes) == len(bodies) >= 1
    for node, theirs in zip(bodies, vtk_meshes):
        ours = skinned_points(read, node, frame)
        assert np.abs(ours - theirs).max() < TOL


def test_vtk_s_importer_skins_and_animates_the_bodies(written):
    motion, _, _, files = written
    _check_vtk_skinning(files["full"], 57, motion.fps)


def test_the_khronos_validator_finds_no_error_and_no_warning(written):
    if validator_command() is None:
        pytest.skip("node or the npm package gltf-validator is absent (scripts/bootstrap.sh installs it)")
    *_, files = written
    reports = validate([files[k] for k in ("glb", "gltf", "full")])
    assert len(reports) == 3
    for r in reports:
        assert (r["errors"], r["warnings"]) == (0, 0), r


def test_the_format_follows_the_extension_and_an_unknown_one_lists_the_known(tmp_path):
    assert motion_format(tmp_path / "a.GLB") == ".glb"
    with pytest.raises(UserError, match=r"'\.fbx'.*known: \.bvh .*\.glb .*\.gltf"):
        save_motion(tmp_path / "a.fbx", _motion(4))
    with pytest.raises(UserError, match="no extension"):
        motion_format(tmp_path / "a", "--out")
    with pytest.raises(UserError, match="one skeleton"):
        save_motion(tmp_path / "a.bvh", _motion(4), contents=GltfContents(mesh=False))
    assert not list(tmp_path.iterdir())
    save_motion(tmp_path / "b.glb", _motion(4))
    assert (tmp_path / "b.glb").read_bytes()[:4] == b"glTF"
    assert [p.name for p in tmp_path.iterdir()] == ["b.glb"]  # no temporary file left


#: One file of each rig family of the shared data (docs/skeleton.md).
SOURCE_RIGS = (
    "dragposer/example.bvh",
    "cmu_mb/01_01.bvh",
    "cmu_daz/indian",
    "cmu_iclone/001_01.bvh",
    "cmu_daz_cgspeed",
)


def _first_bvh(mocap, rel: str):
    path = mocap / rel
    return path if path.is_file() else sorted(path.rglob("*.bvh"))[0]


@pytest.fixture(scope="module")
def source_rig_files(shared_mocap, tmp_path_factory):
    """Per rig family: the clip's first 2 s retargeted, written back onto its rig as BVH
    and as glTF (mesh, a comparison character and the trackers), with the rig's report."""
    from engine.motion.retarget import manifest_fps, retarget, source_frames_needed

    folder = tmp_path_factory.mktemp("gltf_rigs")
    out = {}
    for rel in SOURCE_RIGS:
        path = _first_bvh(shared_mocap, rel)
        raw = load_bvh(path, source_frames_needed(120))
        motion, rep = retarget(raw, manifest_fps(path))
        motion = motion.slice(0, 120)
        ghost = Motion(motion.local_rot[::-1].copy(), motion.root_pos[::-1].copy(), motion.skeleton, motion.fps)
        stem = rel.split("/")[0]
        bvh, glb = folder / f"{stem}.bvh", folder / f"{stem}.glb"
        save_motion(bvh, motion, (raw, rep))
        save_motion(
            glb, motion, (raw, rep), contents=GltfContents(ghosts=(("ik", ghost),), tracking=simulate(motion, "6"))
        )
        out[stem] = (raw, rep, bvh, glb)
    return out


@pytest.mark.shared_data
def test_on_the_source_rig_the_joints_names_and_frames_are_the_bvh_s(source_rig_files):
    for stem, (raw, rep, bvh, glb) in source_rig_files.items():
        back = load_bvh(bvh)
        world = bvh_world_positions(back)
        if rep.profile.root_channels_relative_to_offset:
            world = world + back.offsets[0]  # the rig's root channels count from its OFFSET
        want = world @ np.asarray(rep.basis).T * rep.profile.units_to_m
        read = read_gltf(glb)
        skin = read.doc.skins[0]
        assert [read.doc.nodes[j].name for j in skin.joints] == list(raw.names), stem
        times, _ = read.channels()[(skin.joints[0], "rotation")]
        assert len(times) == back.frames and abs(1 / np.diff(times).mean() - rep.source_fps) < 1e-3, stem
        got = read.world_positions(list(skin.joints), back.frames) @ Y_UP_TO_Z_UP.T
        err = np.abs(got - want).max()
        assert err < TOL, f"{stem}: {err:.2e} m"


@pytest.mark.shared_data
def test_vtk_s_importer_skins_the_source_rigs(source_rig_files):
    for _raw, rep, _bvh, glb in source_rig_files.values():
        _check_vtk_skinning(glb, 31, rep.source_fps)


@pytest.mark.shared_data
def test_the_validator_passes_the_source_rig_files(source_rig_files):
    if validator_command() is None:
        pytest.skip("node or the npm package gltf-validator is absent (scripts/bootstrap.sh installs it)")
    reports = validate([glb for *_, glb in source_rig_files.values()])
    assert len(reports) == len(SOURCE_RIGS)
    for r in reports:
        assert (r["errors"], r["warnings"]) == (0, 0), r
