"""The same CMU take converted from two or three rigs gives the same canonical motion.

Every take the shared manifest lists on several rigs (``cmu_trial``) is converted from each
rig; each pair of copies is aligned in time and heading and compared
(:func:`research.retarget_compare.compare_clips`, table: ``research/cross_rig.py``)."""

from __future__ import annotations

import numpy as np
import pytest

from engine import skeleton as sk
from engine.motion.clip import Motion
from research.retarget_versions import VERSION_5, VERSIONS

pytestmark = pytest.mark.shared_data
#: Canonical frames read per copy (30 s): the longest takes run 40 s on the CMU rig, and
#: their first 30 s keep the test within about a minute on two cores.
MAX_FRAMES = 1800


@pytest.fixture(scope="module")
def every_pair(shared_mocap):
    """Every pair of copies of every multi-rig take, each copy loaded once and each pair
    compared (:func:`research.retarget_compare.compare_clips`, from one alignment shared
    with the split) and split into a constant
    offset per joint and what varies (:func:`research.retarget_ablation.offset_ablation`):
    ``[(take, a, b, difference, ablation)]``."""
    import itertools

    from engine.motion.retarget import CURRENT, load_motion
    from research.retarget_ablation import offset_ablation
    from research.retarget_compare import align_clips, difference, multi_rig_takes

    rows = []
    takes = multi_rig_takes(shared_mocap)
    assert len(takes) >= 81, "the manifest lists 81 takes on two or three rigs"
    for take, paths in takes.items():
        clips = {p: load_motion(shared_mocap / p, strategy=CURRENT, max_frames=MAX_FRAMES) for p in paths}
        for a, b in itertools.combinations(paths, 2):
            aligned = align_clips(clips[a], clips[b])  # once for both: it costs as much as the rest
            rows.append(
                (
                    take,
                    a.split("/")[0],
                    b.split("/")[0],
                    difference(aligned),
                    offset_ablation(clips[a], clips[b], aligned),
                )
            )
    return rows


@pytest.fixture(scope="module")
def cross_rig(every_pair):
    """Every pair of copies of every multi-rig take, compared: ``[(take, a, b, difference)]``."""
    return [row[:4] for row in every_pair]


@pytest.fixture(scope="module")
def offsets_removed(every_pair):
    """Per pair of rigs, the mean over its takes of the mean local-rotation difference once
    each joint's constant offset is removed (:func:`research.retarget_ablation.offset_ablation`)."""
    out: dict[tuple[str, str], list[tuple[float, float]]] = {}
    for _, a, b, _, ab in every_pair:
        out.setdefault((a, b), []).append((float(ab.removed_deg.mean()), float(ab.removed_pos_cm.mean())))
    return {pair: tuple(np.mean(v, axis=0).tolist()) for pair, v in out.items()}


def _joint(rows, name: str) -> np.ndarray:
    return np.array([d.rot_deg[sk.JOINT_INDEX[name]] for *_, d in rows])


@pytest.mark.slow
def test_elbows_bend_alike_on_every_rig(cross_rig):
    """The elbow is its bending plane and angle; the Daz rig's zero pose draws it 17 degrees
    bent, which ``straight_elbows`` takes as its straight rest."""
    for elbow in ("lelbow", "relbow"):
        worst = max(cross_rig, key=lambda r: r[3].rot_deg[sk.JOINT_INDEX[elbow]])
        assert _joint(cross_rig, elbow).max() <= 3.0, (elbow, worst[:3], worst[3].rot_deg[sk.JOINT_INDEX[elbow]])


@pytest.mark.slow
def test_knees_bend_alike_on_nine_takes_in_ten(cross_rig):
    """On the iClone and CMU rigs; the Daz rig draws its knees 7.7 degrees bent in the zero
    pose and its copies bend them 7-9 degrees more in version 4, which leaves them as drawn
    (version 5 reads them straight: test_version_5_knees_bend_alike_on_the_daz_rig_too)."""
    for knee in ("lknee", "rknee"):
        for pair in sorted(
            {(a, b) for _, a, b, _ in cross_rig} - {(a, b) for _, a, b, _ in cross_rig if "daz" in a + b}
        ):
            v = _joint([r for r in cross_rig if (r[1], r[2]) == pair], knee)
            assert np.percentile(v, 90) <= 8.0 and np.median(v) <= 3.5, (knee, pair, np.round(np.sort(v)[-5:], 1))


@pytest.fixture(scope="module")
def daz_legs_v5(shared_mocap):
    """Thigh, knee and toe differences (degrees) of every pair with a Daz copy, version 5:
    ``{(a, b): array (takes, 6)}`` for lhip, lknee, rhip, rknee, ltoe, rtoe."""
    from engine.motion.retarget import load_motion
    from research.retarget_compare import compare_clips, multi_rig_takes

    legs = [sk.JOINT_INDEX[j] for j in ("lhip", "lknee", "rhip", "rknee", "ltoe", "rtoe")]
    out: dict[tuple[str, str], list] = {}
    for paths in multi_rig_takes(shared_mocap).values():
        daz = [p for p in paths if "daz" in p]
        for d in daz:
            a = load_motion(shared_mocap / d, strategy=VERSION_5, max_frames=MAX_FRAMES)
            for other in (p for p in paths if p != d):
                diff = compare_clips(a, load_motion(shared_mocap / other, strategy=VERSION_5, max_frames=MAX_FRAMES))
                out.setdefault((d.split("/")[0], other.split("/")[0]), []).append(diff.rot_deg[legs])
    return {pair: np.array(v) for pair, v in out.items()}


@pytest.mark.slow
def test_version_5_knees_bend_alike_on_the_daz_rig_too(daz_legs_v5):
    """With ``straight_knees`` the Daz copies' knees agree as the iClone and CMU ones do
    (9 takes in 10 within 8 degrees, median within 3.5), and their thighs within 6 degrees
    on the median (version 4: knees 7.2 / 8.6, thighs 7.6 / 8.4)."""
    assert len(daz_legs_v5) == 2
    for pair, v in daz_legs_v5.items():
        knees, thighs = v[:, [1, 3]], v[:, [0, 2]]
        assert np.percentile(knees, 90) <= 8.0 and np.median(knees) <= 3.5, (
            pair,
            np.round(np.sort(knees.ravel())[-5:], 1),
        )
        assert np.median(thighs) <= 6.0, (pair, round(float(np.median(thighs)), 1))


@pytest.mark.slow
def test_version_5_toes_agree_on_the_daz_rig(daz_legs_v5):
    """With the canonical toe tip on the sole's line, the Daz copies' toes (the rig has no
    toe joint) agree with the others within 9 degrees on the median (version 4: 21-27)."""
    for pair, v in daz_legs_v5.items():
        assert np.median(v[:, 4:]) <= 9.0, (pair, round(float(np.median(v[:, 4:])), 1))


@pytest.mark.slow
@pytest.mark.xfail(
    strict=True,
    reason=(
        "most of the difference is a constant offset per joint (removed: 2.6-3.7 deg mean per pair of rigs, "
        "test_what_varies_over_the_clip_is_small): hand direction and knuckle line (wrists 29-41 deg on the "
        "Daz pairs), the Daz rig's missing toe (21-27), eye height (head 15-31), the head-frame rule (lower "
        "neck 20-24); the Daz copies of 009_10 and 007_12 are other conversions (thighs 30-69 deg, 12-28 cm)"
    ),
)
def test_every_take_meets_the_cross_rig_targets(cross_rig):
    """Issue targets: mean local-rotation difference <= 3 deg, no joint's mean > 8 deg, and
    root-relative positions (one skeleton, one height) within 1.5 cm."""
    bad = [
        (t, a, b, round(d.rot_mean, 1), d.rot_worst, round(d.pos_mean, 2))
        for t, a, b, d in cross_rig
        if d.rot_mean > 3 or d.rot_worst[1] > 8 or d.pos_mean > 1.5
    ]
    assert not bad, f"{len(bad)} of {len(cross_rig)} pairs miss: {bad[:5]}"


@pytest.mark.slow
def test_what_varies_over_the_clip_is_small(offsets_removed):
    """The differences are mostly constant over each clip (where each rig puts its
    landmarks): once each joint's constant offset is removed, the copies on the Daz rig
    agree with the others within 3 degrees on average, the iClone and CMU copies within 4
    (the CMU rig's hands and neck follow rules, docs/skeleton.md); the iClone and CMU copies'
    root-relative positions then meet the 1.5 cm target."""
    limits = {("cmu_daz_cgspeed", "cmu_iclone"): 3.0, ("cmu_daz_cgspeed", "cmu_mb"): 3.0, ("cmu_iclone", "cmu_mb"): 4.0}
    assert set(offsets_removed) == set(limits)
    for pair, limit in limits.items():
        assert offsets_removed[pair][0] <= limit, (pair, round(offsets_removed[pair][0], 2))
    assert offsets_removed[("cmu_iclone", "cmu_mb")][1] <= 1.5, offsets_removed


def test_alignment_finds_the_offset_and_heading_of_a_copy():
    """A clip against a copy that starts 7 frames (120 fps) later and faces 40 degrees away."""
    from engine.kinematics import quaternion as Q
    from engine.motion.retarget import resample_motion
    from research.retarget_compare import compare_clips
    from tests.engine.test_retarget_body import canonical_walk

    local, root = canonical_walk(240)
    clip = resample_motion(Motion(local, root), 120.0)
    turn = Q.from_axis_angle(np.array([0.0, 0.0, 1.0]), np.radians(40.0))
    rot = clip.local_rot[7:].copy()
    rot[:, 0] = Q.mul(np.broadcast_to(turn, rot[:, 0].shape), rot[:, 0])
    copy = Motion(
        rot, Q.rotate(np.broadcast_to(turn, clip.root_pos[7:].shape[:-1] + (4,)), clip.root_pos[7:]), fps=120.0
    )
    d = compare_clips(clip, copy)
    assert d.shift == -7 and abs(d.heading_deg - 40.0) < 0.5
    assert d.rot_deg.max() < 0.1 and d.pos_cm.max() < 0.05
    bent = copy.local_rot.copy()
    bent[:, sk.JOINT_INDEX["lelbow"]] = Q.mul(
        bent[:, sk.JOINT_INDEX["lelbow"]], Q.from_axis_angle(np.array([0.0, 0.0, 1.0]), np.radians(10.0))
    )
    assert abs(compare_clips(clip, Motion(bent, copy.root_pos, fps=120.0)).rot_deg[sk.JOINT_INDEX["lelbow"]] - 10) < 0.5


def test_ablation_separates_a_constant_offset_from_a_disagreement():
    """A copy whose left hand frame is turned a constant 30 degrees about the bone (a knuckle
    line placed differently) and whose right knee bends 10 degrees more on every other
    second: the offset is removed and read as twist, the knee's varying part stays."""
    from engine.kinematics import quaternion as Q
    from engine.kinematics.fk import fk, local_from_global
    from engine.motion.joint_stats import joint_axis
    from engine.motion.retarget import resample_motion
    from research.retarget_ablation import offset_ablation
    from tests.engine.test_retarget_body import canonical_walk

    local, root = canonical_walk(240)
    clip = resample_motion(Motion(local, root), 120.0)
    glob = fk(clip.local_rot, clip.root_pos, sk.REST_OFFSETS)[1]
    w, k = sk.JOINT_INDEX["lwrist"], sk.JOINT_INDEX["rknee"]
    glob[:, w] = Q.mul(glob[:, w], Q.from_axis_angle(joint_axis("lwrist"), np.radians(30.0)))
    rot = Q.normalize(local_from_global(glob))
    on = (np.arange(len(rot)) // 120) % 2 == 1
    rot[on, k] = Q.mul(rot[on, k], Q.from_axis_angle(np.array([1.0, 0.0, 0.0]), np.radians(-10.0)))
    ab = offset_ablation(clip, Motion(rot, clip.root_pos, fps=120.0))
    assert abs(ab.raw_deg[w] - 30.0) < 0.5 and ab.removed_deg[w] < 0.1
    assert abs(ab.offset_twist_deg[w] - 30.0) < 0.5 and ab.offset_swing_deg[w] < 0.5
    assert ab.raw_deg[k] > 4.0 and ab.removed_deg[k] > 4.0  # half the frames at +-5 around the mean
    others = [j for j in range(sk.NUM_JOINTS) if j not in (w, k, sk.JOINT_INDEX["rankle"])]
    assert ab.removed_deg[others].max() < 0.1 and ab.removed_pos_cm[: sk.JOINT_INDEX["rknee"]].max() < 0.05


def test_one_alignment_shared_by_the_difference_and_the_ablation_gives_their_own_results():
    """``every_pair`` aligns each pair once for :func:`research.retarget_compare.difference`
    and ``offset_ablation(..., aligned=)``: the figures are those of ``compare_clips`` and
    of ``offset_ablation`` aligning on their own, to the bit."""
    import dataclasses

    from engine.kinematics import quaternion as Q
    from engine.motion.retarget import resample_motion
    from research.retarget_ablation import offset_ablation
    from research.retarget_compare import align_clips, compare_clips, difference
    from tests.engine.test_retarget_body import canonical_walk

    local, root = canonical_walk(240)
    clip = resample_motion(Motion(local, root), 120.0)
    rot = clip.local_rot[5:].copy()
    knee = sk.JOINT_INDEX["rknee"]
    rot[:, knee] = Q.mul(rot[:, knee], Q.from_axis_angle(np.array([1.0, 0.0, 0.0]), np.radians(-8.0)))
    copy = Motion(rot, clip.root_pos[5:], fps=120.0)
    aligned = align_clips(clip, copy)
    for shared, own in (
        (difference(aligned), compare_clips(clip, copy)),
        (offset_ablation(clip, copy, aligned), offset_ablation(clip, copy)),
    ):
        for f in dataclasses.fields(own):
            assert np.array_equal(getattr(shared, f.name), getattr(own, f.name)), f.name
    assert difference(aligned).rot_deg[knee] > 7.0  # the pair differs: the check above can fail


@pytest.mark.parametrize("daz, other", [("07_03", "cmu_iclone/007_03.bvh"), ("02_01", "cmu_mb/02_01.bvh")])
def test_daz_legs_drawn_bent_read_straight(shared_mocap, daz, other):
    """The Daz rig draws its knees 7.7 degrees bent about the hip-to-ankle line and its
    copies bend them that much more than the same take on the iClone and CMU rigs
    (version 4); ``straight_knees`` (version 5) reads its legs straight along that line."""
    from engine.motion.retarget import load_motion
    from research.retarget_compare import compare_clips

    ref = load_motion(shared_mocap / other, strategy=VERSION_5, max_frames=300)
    legs = [sk.JOINT_INDEX[j] for j in ("lhip", "lknee", "rhip", "rknee")]
    diff = {
        v: compare_clips(
            load_motion(shared_mocap / f"cmu_daz_cgspeed/{daz}.bvh", strategy=VERSIONS[v], max_frames=300), ref
        )
        for v in (4, 5)
    }
    assert diff[4].rot_deg[legs].mean() > 6.0, np.round(diff[4].rot_deg[legs], 1)
    assert diff[5].rot_deg[legs].mean() < 4.0, np.round(diff[5].rot_deg[legs], 1)
    assert diff[5].pos_mean <= diff[4].pos_mean + 0.1


def test_toe_tips_on_the_sole_line_make_the_daz_toes_agree(shared_mocap):
    """The Daz rig has no toe joint (its toes never bend); the iClone and CMU rigs put their
    toe tips on the sole's line, which version 4 read as toes bent 19-35 degrees against the
    canonical end site (on the floor). Version 5's sole-line tip makes the Daz copy's toes
    agree and leaves the iClone / CMU agreement as it was."""
    from engine.motion.retarget import load_motion
    from research.retarget_compare import compare_clips

    toes = [sk.JOINT_INDEX["ltoe"], sk.JOINT_INDEX["rtoe"]]
    clips = {
        (rig, v): load_motion(shared_mocap / path, strategy=VERSIONS[v], max_frames=300)
        for rig, path in (
            ("daz", "cmu_daz_cgspeed/07_03.bvh"),
            ("iclone", "cmu_iclone/007_03.bvh"),
            ("mb", "cmu_mb/07_03.bvh"),
        )
        for v in (4, 5)
    }
    daz = {v: compare_clips(clips["daz", v], clips["iclone", v]).rot_deg[toes] for v in (4, 5)}
    assert daz[4].min() > 15.0 and (daz[5] < daz[4] / 2).all() and daz[5].mean() < 9.0, (
        daz[4].round(1),
        daz[5].round(1),
    )
    same = {v: compare_clips(clips["iclone", v], clips["mb", v]).rot_deg[toes] for v in (4, 5)}
    assert np.abs(same[5] - same[4]).max() < 1.5, (same[4].round(1), same[5].round(1))
