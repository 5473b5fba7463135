"""The same CMU take converted from two or three rigs gives the same canonical motion.

Every take the shared manifest lists on several rigs (``cmu_trial``) is converted from each
rig; each pair of copies is aligned in time and heading and compared
(:func:`engine.motion.retarget_compare.compare_clips`, table: ``scripts/cross_rig.py``)."""

from __future__ import annotations

import numpy as np
import pytest

from engine import skeleton as sk
from engine.motion.clip import Motion

pytestmark = pytest.mark.shared_data
#: Canonical frames read per copy (30 s): the longest takes run 40 s on the CMU rig, and
#: their first 30 s keep the test within about a minute on two cores.
MAX_FRAMES = 1800


@pytest.fixture(scope="module")
def cross_rig(shared_mocap):
    """Every pair of copies of every multi-rig take, compared once: ``[(take, a, b, difference)]``."""
    import itertools

    from engine.motion.retarget import RETARGET_VERSION, load_motion
    from engine.motion.retarget_compare import compare_clips, multi_rig_takes

    rows = []
    takes = multi_rig_takes(shared_mocap)
    assert len(takes) >= 81, "the manifest lists 81 takes on two or three rigs"
    for take, paths in takes.items():
        clips = {p: load_motion(shared_mocap / p, version=RETARGET_VERSION, max_frames=MAX_FRAMES) for p in paths}
        for a, b in itertools.combinations(paths, 2):
            rows.append((take, a.split("/")[0], b.split("/")[0], compare_clips(clips[a], clips[b])))
    return rows


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
    pose and its copies bend them 7-9 degrees more (left as drawn: docs/skeleton.md)."""
    for knee in ("lknee", "rknee"):
        for pair in sorted({(a, b) for _, a, b, _ in cross_rig} - {(a, b) for _, a, b, _ in cross_rig if "daz" in a + b}):
            v = _joint([r for r in cross_rig if (r[1], r[2]) == pair], knee)
            assert np.percentile(v, 90) <= 8.0 and np.median(v) <= 3.5, (knee, pair, np.round(np.sort(v)[-5:], 1))


@pytest.mark.slow
@pytest.mark.xfail(strict=True, reason=(
    "the rigs place their landmarks differently and these offsets are constant over each clip "
    "(std 1-6 deg): iClone's knuckle line is turned 31 deg from the Daz rig's, the eyes 16 deg "
    "(head), the toe tips 25-36 deg; the CMU rig has no eyes or knuckles rigid with the hand"))
def test_every_take_meets_the_cross_rig_targets(cross_rig):
    """Issue targets: mean local-rotation difference <= 3 deg, no joint's mean > 8 deg, and
    root-relative positions (one skeleton, one height) within 1.5 cm."""
    bad = [(t, a, b, round(d.rot_mean, 1), d.rot_worst, round(d.pos_mean, 2)) for t, a, b, d in cross_rig
           if d.rot_mean > 3 or d.rot_worst[1] > 8 or d.pos_mean > 1.5]  # fmt: skip
    assert not bad, f"{len(bad)} of {len(cross_rig)} pairs miss: {bad[:5]}"


def test_alignment_finds_the_offset_and_heading_of_a_copy():
    """A clip against a copy that starts 7 frames (120 fps) later and faces 40 degrees away."""
    from engine.kinematics import quaternion as Q
    from engine.motion.retarget import resample_motion
    from engine.motion.retarget_compare import compare_clips
    from tests.engine.test_retarget_body import canonical_walk

    local, root = canonical_walk(240)
    clip = resample_motion(Motion(local, root), 120.0)
    turn = Q.from_axis_angle(np.array([0.0, 0.0, 1.0]), np.radians(40.0))
    rot = clip.local_rot[7:].copy()
    rot[:, 0] = Q.mul(np.broadcast_to(turn, rot[:, 0].shape), rot[:, 0])
    copy = Motion(rot, Q.rotate(np.broadcast_to(turn, clip.root_pos[7:].shape[:-1] + (4,)), clip.root_pos[7:]),
                  fps=120.0)  # fmt: skip
    d = compare_clips(clip, copy)
    assert d.shift == -7 and abs(d.heading_deg - 40.0) < 0.5
    assert d.rot_deg.max() < 0.1 and d.pos_cm.max() < 0.05
    bent = copy.local_rot.copy()
    bent[:, sk.JOINT_INDEX["lelbow"]] = Q.mul(bent[:, sk.JOINT_INDEX["lelbow"]], Q.from_axis_angle(
        np.array([0.0, 0.0, 1.0]), np.radians(10.0)))  # fmt: skip
    assert abs(compare_clips(clip, Motion(bent, copy.root_pos, fps=120.0)).rot_deg[sk.JOINT_INDEX["lelbow"]] - 10) < 0.5
