"""True proportions, natural rotations and the way back, on the real shared clips.

* the canonical hinge axes in ``engine.motion.retarget_frames`` are what DragPoser's own clips show;
* retargeted knees bend about their local x axis with a few degrees of twist, and thighs
  carry no large twist the shin undoes (+114/+61 degrees on the Daz takes would fail);
* the spine and clavicles have one convention on every rig: near identity while the
  torso is upright (not the iClone upper back bent 80 degrees where the Daz rig, lacking
  that joint, stays straight);
* every shared file loads as a finite canonical clip, and heights match the source within
  3 % (every file, loaded once for these sweeps: slow);
* a clip written back onto its own rig reproduces the source's mapped joints within 1 cm.
"""

from __future__ import annotations

import numpy as np
import pytest

from engine import skeleton as sk
from engine.kinematics.fk import fk
from engine.motion.joint_stats import joint_report, limb_hinge
from engine.motion.retarget_frames import CANON_HINGE, LIMBS

pytestmark = pytest.mark.shared_data

CLIPS = (
    "cmu_daz/martial/03.bvh",
    "cmu_daz/indian/04.bvh",
    "cmu_daz/salsa/01.bvh",
    "cmu_iclone/007_02.bvh",
    "cmu_iclone/002_01.bvh",
    "cmu_iclone/005_06.bvh",
)


def _load(mocap, rel):
    from engine.motion.retarget import CURRENT, load_with_report

    return load_with_report(mocap / rel, strategy=CURRENT)


@pytest.mark.parametrize("rel", CLIPS)
def test_upright_spine_and_clavicles_are_near_identity_on_every_rig(shared_mocap, rel):
    motion, _ = _load(shared_mocap, rel)
    pos, _ = motion.fk()
    up = pos[:, sk.JOINT_INDEX["lowerneck"]] - pos[:, 0]
    upright = up[:, 2] / np.linalg.norm(up, axis=-1) > np.cos(np.radians(10))
    assert upright.mean() > 0.3, "the clip should stand upright part of the time"
    for joint in ("lowerback", "upperback", "chest", "lclavicle", "rclavicle"):
        q = motion.local_rot[upright, sk.JOINT_INDEX[joint]]
        q = q * np.sign(q[:, :1] + 1e-12)  # the hemisphere of identity
        mean = q.mean(0) / np.linalg.norm(q.mean(0))
        angle = np.degrees(2 * np.arccos(min(1.0, abs(mean[0]))))
        assert angle < 10, f"{rel}: {joint}'s mean upright rotation is {angle:.0f} deg from identity"


def test_canonical_hinges_are_those_of_dragposers_clips(shared_mocap):
    from engine.motion.retarget import load_motion

    found: dict[str, list] = {}
    for name in ("example.bvh", "example_2.bvh", "example_3.bvh"):
        pos, rot = load_motion(shared_mocap / "dragposer" / name).fk()
        for a, b, c in LIMBS:
            ia, ib, ic = (sk.JOINT_INDEX[k] for k in (a, b, c))
            bend = np.cross(pos[:, ib] - pos[:, ia], pos[:, ic] - pos[:, ib])
            hp, hc = limb_hinge(rot[:, ia], rot[:, ib], bend)
            found.setdefault(a, []).append(hp)
            found.setdefault(b, []).append(hc)
    for joint, axes in found.items():
        mean = np.mean(axes, axis=0)
        assert np.allclose(mean / np.linalg.norm(mean), CANON_HINGE[joint], atol=0.002), joint


@pytest.mark.parametrize("rel", CLIPS)
def test_limbs_rotate_like_the_canonical_clips(shared_mocap, rel):
    motion, _ = _load(shared_mocap, rel)
    rep = joint_report(motion.local_rot, motion.skeleton.offsets)
    # DragPoser's own clips: knee hinge |x| 0.96-1.0, knee twist medians -21..+9 degrees,
    # thigh twist medians -3..0 degrees
    for knee in ("lknee", "rknee"):
        assert abs(rep[knee]["hinge"][0]) > 0.9, (rel, knee, rep[knee])
        assert abs(rep[knee]["twist_median"]) < 25, (rel, knee, rep[knee])
    for thigh in ("lhip", "rhip"):
        assert abs(rep[thigh]["twist_median"]) < 35, (rel, thigh, rep[thigh])


# The CMU rig's LowerBack (folded into the canonical lower back) moves Spine up to 1.4 cm
# about the hips; the canonical skeleton holds that offset fixed, so its clip is up to
# 1.7 cm off the source there (the write-back itself adds nothing: it lands every mapped
# joint on the canonical clip's).
@pytest.mark.parametrize(
    "rel, tol_cm",
    [
        ("cmu_iclone/007_02.bvh", 1.0),
        ("cmu_iclone/002_01.bvh", 1.0),
        ("cmu_daz/salsa/01.bvh", 1.0),
        ("cmu_daz_cgspeed/07_03.bvh", 1.0),
        ("cmu_mb/07_03.bvh", 2.0),
    ],
)
def test_written_back_onto_the_source_rig_within_1cm(shared_mocap, tmp_path, rel, tol_cm):
    """Each rig family (iClone, its 101-joint variant, Daz at 60 and 120 fps, the CMU rig at
    120 fps): source -> canonical -> source over the whole clip. Written at 60 fps, the
    canonical rate, every written frame is one the canonical clip holds (at 120 fps the
    frames between would add the resampling's own error, up to 1.7 cm on a walk)."""
    from engine.motion.bvh import load_bvh
    from engine.motion.retarget import CURRENT, manifest_fps, retarget
    from engine.motion.write_back import save_on_source_rig

    raw = load_bvh(shared_mocap / rel)
    motion, report = retarget(raw, manifest_fps(shared_mocap / rel), strategy=CURRENT)
    save_on_source_rig(tmp_path / "back.bvh", motion, raw, report, fps=60.0)
    back = load_bvh(tmp_path / "back.bvh")
    step = round(report.source_fps / 60.0)
    assert abs(back.fps - 60.0) < 0.01 and step * 60.0 == report.source_fps
    prof = report.profile

    def world(r, skip):
        p = r.positions[skip:, 0].copy()
        if prof.root_channels_relative_to_offset:
            p += r.offsets[0]
        return fk(r.local_quaternions()[skip:], p, r.offsets, list(r.parents))[0]

    a, b = world(raw, report.skip)[::step], world(back, 0)
    n = min(len(a), len(b))
    assert n >= len(a) - 1, "the written file covers the clip"
    idx = [raw.names.index(s) for s in prof.joints.values()]
    err = np.linalg.norm(a[:n, idx] - b[:n, idx], axis=-1) * prof.units_to_m
    assert err.max() < tol_cm / 100 and err.mean() < 0.01, f"{rel}: {100 * err.max():.2f} cm"


FAMILIES = ("cmu_daz", "cmu_daz_cgspeed", "cmu_iclone", "cmu_mb")


@pytest.fixture(scope="module")
def every_shared_clip(shared_mocap):
    """Each file the manifest lists, loaded once (as ``info`` loads it): ``(per-folder file
    counts, heights, summary table, files that load short or not finite)``. The list comes
    from the manifest, so a folder added to the shared data is covered without editing
    these tests."""
    import json

    from engine.motion.joint_stats import summarize
    from engine.motion.retarget import CURRENT, load_with_report

    listed = json.loads((shared_mocap / "manifest.json").read_text())["files"]
    expected = sorted(entry["path"].removeprefix("mocap/") for entry in listed)
    files = sorted(shared_mocap.rglob("*.bvh"))
    assert [str(p.relative_to(shared_mocap)) for p in files] == expected, "the shared data differs from its manifest"
    counts: dict[str, int] = {}
    heights: dict[str, tuple[float, float]] = {}
    groups: dict[str, dict] = {}
    bad: list[str] = []
    for path in files:
        rel = path.relative_to(shared_mocap)
        counts[rel.parts[0]] = counts.get(rel.parts[0], 0) + 1
        motion, rep = load_with_report(path, strategy=CURRENT)
        heights[str(rel)] = (rep.height_m, rep.source_height_m)
        if len(motion) <= 10 or not np.isfinite(motion.positions()).all():
            bad.append(str(rel))
        groups.setdefault(rel.parts[0], {})[str(rel)] = joint_report(motion.local_rot, motion.skeleton.offsets)
    return counts, heights, summarize(groups, "dragposer"), bad


@pytest.mark.slow
def test_every_shared_file_loads_as_a_finite_clip(every_shared_clip):
    assert not every_shared_clip[3], f"short or not finite once loaded: {every_shared_clip[3]}"


@pytest.mark.slow
def test_every_shared_clip_keeps_its_height(every_shared_clip):
    counts, heights, table, _ = every_shared_clip
    assert set(counts) == {"dragposer", *FAMILIES}, "a new folder needs its family's rotation check below"
    assert {g: table["lknee"][g]["clips"] for g in counts} == counts
    off = {rel: h for rel, h in heights.items() if abs(h[0] / h[1] - 1) >= 0.03}
    assert not off, f"heights more than 3 % from the source's (canonical, source in m): {off}"


@pytest.mark.slow
@pytest.mark.parametrize("family", FAMILIES)
def test_every_shared_clip_rotates_like_the_canonical_clips(every_shared_clip, family):
    """Per joint, the hinge axis and twist of each rig family against DragPoser's own clips
    (``engine.motion.joint_stats.summarize``, the figures of docs/skeleton.md: ``research/joint_stats.py``)."""
    table = every_shared_clip[2]
    for knee in ("lknee", "rknee"):  # the hinge of every clip, with DragPoser's few degrees of twist
        row = table[knee][family]
        assert row["hinge_alignment_min"] > 0.9 and -25 < row["twist_median"][0] <= row["twist_median"][1] < 15, (
            family,
            knee,
            row,
        )
    for elbow in ("lelbow", "relbow"):  # per family; the left elbows of iClone 007_* differ (docs)
        row = table[elbow][family]
        assert row["hinge_alignment_median"] > 0.9 and max(map(abs, row["twist_median"])) < 25, (family, elbow, row)
    for thigh in ("lhip", "rhip"):  # no large twist the shin undoes (not +114/+61 degrees)
        assert max(map(abs, table[thigh][family]["twist_median"])) < 35, (family, thigh, table[thigh][family])


def test_the_save_message_names_the_rest_frames_a_source_rig_file_lacks(shared_mocap):
    """A Daz clip's profile skips its 10-frame rest pose on loading: written back onto its
    rig, the file lacks those frames, and the message that says it was written says so."""
    from engine.studio.export import skipped_note, source_rig

    _, report = source_rig(shared_mocap / "cmu_daz/salsa/01.bvh")
    assert report.skip == 10
    assert "first 10 frames" in skipped_note(report) and "frame i + 10" in skipped_note(report)
    _, iclone = source_rig(shared_mocap / "cmu_iclone/002_01.bvh")
    assert iclone.skip == 0 and skipped_note(iclone) == ""
