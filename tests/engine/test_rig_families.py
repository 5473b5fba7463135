"""Any humanoid BVH: automatic mapping, true proportions, natural rotations, back onto its rig.

Synthetic files on every naming family (``rig_fixtures``) are mapped without a
profile, retargeted (their height kept within 3 %), written back onto their own rig
(mapped joints within 1 cm), and their knees bend about the canonical local x axis.
"""

from __future__ import annotations

import json

import numpy as np
import pytest

from engine import skeleton as sk
from engine.errors import RigError
from engine.kinematics.fk import fk
from engine.motion.bvh import load_bvh
from engine.motion.joint_stats import joint_report
from engine.motion.retarget import retarget
from engine.motion.rigs import resolve_rig
from engine.motion.rigs.automap import split_name
from engine.motion.write_back import save_on_source_rig

from .rig_fixtures import EXPECTED, FAMILIES, family_rows, write_family_bvh

#: Canonical joints each family's rig lacks (two-bone spines, Daz's missing toes).
LACKS = {"cmu": {"upperback"}, "joint_root": {"upperback"}, "daz": {"upperback", "ltoe", "rtoe"}}


@pytest.fixture(scope="module", params=FAMILIES)
def family(request, tmp_path_factory):
    path = write_family_bvh(tmp_path_factory.mktemp(request.param) / f"{request.param}.bvh", request.param)
    raw = load_bvh(path)
    # the automatic mapping, even where a shipped profile also matches (the real Daz header)
    motion, report = retarget(raw, profile=resolve_rig(raw, profiles=[]))
    return request.param, path, raw, motion, report


def _world(raw, relative: bool):
    pos = raw.positions[:, 0].copy()
    if relative:
        pos += raw.offsets[0]
    return fk(raw.local_quaternions(), pos, raw.offsets, list(raw.parents))[0]


def test_every_family_maps_without_a_profile(family):
    name, _, raw, _, report = family
    prof = report.profile
    assert prof.name == "auto"
    assert set(sk.JOINT_NAMES) - set(prof.joints) == LACKS.get(name, set())
    for canon, src in EXPECTED[name].items():
        assert prof.joints[canon] == src, canon
    _, _, units, up = family_rows(name)
    assert prof.units_to_m == pytest.approx(units)
    assert prof.up == "+" + up


def test_the_real_daz_header_is_the_shipped_cmu_daz_rig(tmp_path):
    """The Daz fixture's header is the rig of ../shared/data's cmu_daz clips: its profile wins."""
    raw = load_bvh(write_family_bvh(tmp_path / "daz.bvh", "daz", frames=30))
    assert resolve_rig(raw).name == "cmu_daz"
    auto = resolve_rig(raw, profiles=[])
    assert {c: auto.joints[c] for c in resolve_rig(raw).joints} == resolve_rig(raw).joints


def test_height_is_the_subjects(family):
    name, _, raw, motion, report = family
    assert abs(report.height_m / report.source_height_m - 1) < 0.03
    # per-bone proportions are the subject's: thigh, shin, upper arm, forearm lengths
    prof = report.profile
    for bone, (a, b) in {
        "lknee": ("lhip", "lknee"),
        "lankle": ("lknee", "lankle"),
        "relbow": ("rshoulder", "relbow"),
        "rwrist": ("relbow", "rwrist"),
    }.items():
        i, j = raw.names.index(prof.joints[a]), raw.names.index(prof.joints[b])
        chain, k = 0.0, j
        while k != i:
            chain, k = chain + np.linalg.norm(raw.offsets[k]), raw.parents[k]
        length = np.linalg.norm(motion.skeleton.offsets[sk.JOINT_INDEX[bone]])
        assert length == pytest.approx(chain * prof.units_to_m, abs=0.005), (name, bone)


def test_bone_vectors_follow_the_source(family):
    name, _, raw, motion, report = family
    prof = report.profile
    src = _world(raw, prof.root_channels_relative_to_offset) @ report.basis.T * prof.units_to_m
    ours = motion.positions()
    for a, b in (
        ("lhip", "lknee"),
        ("lknee", "lankle"),
        ("rshoulder", "relbow"),
        ("relbow", "rwrist"),
        ("root", "lhip"),
        ("chest", "lclavicle"),
    ):
        s = src[:, raw.names.index(prof.joints[b])] - src[:, raw.names.index(prof.joints[a])]
        c = ours[:, sk.JOINT_INDEX[b]] - ours[:, sk.JOINT_INDEX[a]]
        assert np.linalg.norm(s - c, axis=-1).max() < 0.01, (name, a, b)


def test_round_trip_onto_the_source_rig(family, tmp_path):
    name, path, raw, motion, report = family
    out = tmp_path / "back.bvh"
    save_on_source_rig(out, motion, raw, report)
    back = load_bvh(out)
    assert back.names == raw.names and np.allclose(back.offsets, raw.offsets, atol=1e-5)
    rel = report.profile.root_channels_relative_to_offset
    a, b = _world(raw, rel), _world(back, rel)
    idx = [raw.names.index(s) for s in report.profile.joints.values()]
    err = np.linalg.norm(a[:, idx] - b[:, idx], axis=-1) * report.profile.units_to_m
    assert err.max() < 0.01, name


def test_knees_hinge_about_local_x_with_little_twist(family):
    name, _, _, motion, _ = family
    rep = joint_report(motion.local_rot, motion.skeleton.offsets)
    for knee in ("lknee", "rknee"):
        # > 0.85, not 0.99: the CMU rig's shins lean 20 degrees in its rest pose and the
        # synthetic knees turn about the rig's x axis, so that hinge is oblique to the shin
        assert abs(rep[knee]["hinge"][0]) > 0.85, (name, knee, rep[knee])
        assert rep[knee]["hinge_share"] > 0.9
    for thigh in ("lhip", "rhip"):  # the synthetic thighs twist by at most 4 degrees
        assert abs(rep[thigh]["twist_median"]) < 20, (name, thigh, rep[thigh])


@pytest.mark.parametrize(
    ("name", "side", "core"),
    [
        ("mixamorig:LeftUpLeg", "l", "upleg"),
        ("CC_Base_R_Thigh", "r", "ccbasethigh"),
        ("thigh_l", "l", "thigh"),
        ("lShldr", "l", "shldr"),
        ("RHipJoint", "r", "hipjoint"),
        ("left_knee", "l", "knee"),
        ("Bip01 R Foot", "r", "bip01foot"),
        ("Spine2", None, "spine2"),
        ("rankle", "r", "ankle"),
        ("UpperArm_R", "r", "upperarm"),
    ],
)
def test_names_split_into_side_and_core(name, side, core):
    assert split_name(name) == (side, core)


def test_unmappable_file_lists_missing_joints_and_its_own(tmp_path):
    path = tmp_path / "blob.bvh"
    path.write_text(
        "HIERARCHY\nROOT Body\n{\n OFFSET 0 0 0\n CHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation\n"
        " JOINT Tentacle\n {\n  OFFSET 0 10 0\n  CHANNELS 3 Zrotation Xrotation Yrotation\n"
        "  End Site\n  {\n   OFFSET 0 5 0\n  }\n }\n}\nMOTION\nFrames: 2\nFrame Time: 0.0333\n"
        "0 0 0 0 0 0 0 0 0\n0 0 0 0 0 0 0 0 0\n"
    )
    with pytest.raises(RigError) as err:
        resolve_rig(load_bvh(path))
    msg = str(err.value)
    assert str(path) in msg and "lankle" in msg and "upperneck" in msg and "Body, Tentacle" in msg
    assert "rig suggest" in msg and "--rig-map" in msg


def test_rig_suggest_writes_a_mapping_that_loads_back(tmp_path, family):
    from engine.cli.main import main

    name, path, raw, _, report = family
    out = tmp_path / "map.toml"
    assert main(["rig", "suggest", str(path), "--out", str(out)]) == 0
    text = out.read_text()
    assert "# " in text and "[joints]" in text  # reasons are written as comments
    prof = resolve_rig(raw, out)
    assert prof.joints == report.profile.joints and prof.units_to_m == report.profile.units_to_m


def test_rig_map_is_checked_and_wins(tmp_path):
    from engine.cli.main import main

    path = write_family_bvh(tmp_path / "m.bvh", "lafan")
    good = tmp_path / "map.toml"
    main(["rig", "suggest", str(path), "--out", str(good)])
    swapped = good.read_text().replace('lknee = "LeftLeg"', 'lknee = "RightLeg"')
    bad = tmp_path / "bad.toml"
    bad.write_text(swapped)
    with pytest.raises(RigError, match="lknee=RightLeg does not descend from lhip=LeftUpLeg"):
        resolve_rig(load_bvh(path), bad)
    typo = tmp_path / "typo.toml"
    typo.write_text(good.read_text().replace('"LeftFoot"', '"LeftFoo"'))
    with pytest.raises(RigError, match="LeftFoo"):
        resolve_rig(load_bvh(path), typo)


def test_info_json_is_one_object_always(tmp_path, capsys):
    from engine.cli.main import main

    path = write_family_bvh(tmp_path / "x.bvh", "xsens")
    assert main(["info", "--json", str(path)]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["rig"] == "auto" and out["mapping"]["chest"] == "T8"
    assert abs(out["height_m"] / out["source_height_m"] - 1) < 0.03
    broken = tmp_path / "broken.bvh"
    broken.write_text("HIERARCHY\nROOT a\n{\n")
    assert main(["info", "--json", str(broken)]) == 2
    out = json.loads(capsys.readouterr().out)
    assert set(out) == {"file", "error"} and "broken.bvh" in out["error"]


def test_convert_writes_the_canonical_clip(tmp_path):
    from engine.cli.main import main
    from engine.motion.retarget import load_with_report

    src = write_family_bvh(tmp_path / "c.bvh", "cmu", fps=120.0)
    out = tmp_path / "canon.bvh"
    assert main(["convert", str(src), "--out", str(out)]) == 0
    motion, rep = load_with_report(out)
    assert rep.rig == "dragposer" and motion.fps == 60.0
    _, orig = load_with_report(src)
    assert rep.height_m == pytest.approx(orig.height_m, rel=0.03)
    assert main(["convert", str(src), "--out", str(tmp_path / "c30.bvh"), "--fps", "30"]) == 0
    assert load_bvh(tmp_path / "c30.bvh").fps == pytest.approx(30.0, rel=1e-3)
    assert not list(tmp_path.glob("*.tmp"))


def test_reconstruct_on_source_rig(tmp_path):
    from engine.cli.main import main

    src = write_family_bvh(tmp_path / "u.bvh", "unreal", frames=40)
    out = tmp_path / "rec.bvh"
    code = main(["reconstruct", str(src), "--out", str(out), "--on-source-rig", "--method", "ik", "--no-progress"])
    assert code == 0
    back = load_bvh(out)
    raw = load_bvh(src)
    assert back.names == raw.names and back.frames == 40
    # the reconstruction stays on the input's floor and path: hips within 10 cm of the source's
    idx = raw.names.index("pelvis")
    err = np.linalg.norm(_world(back, False)[:, idx] - _world(raw, False)[:, idx], axis=-1) * 0.01
    assert np.median(err) < 0.1
