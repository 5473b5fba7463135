"""The classical IK baseline: reaches its targets, keeps bones, works for every preset."""

from __future__ import annotations

import numpy as np
import pytest

from engine import skeleton as sk
from engine.errors import UserError
from engine.kinematics import quaternion as Q
from engine.methods import available_methods, get_method, register_method, run_method
from engine.methods.ik import IKMethod, two_bone_mid
from engine.tracking import PRESETS, simulate

LIMBS = [(15, 16, 17), (19, 20, 21), (1, 2, 3), (5, 6, 7)]


def _bone_lengths(pos: np.ndarray) -> np.ndarray:
    return np.linalg.norm(pos[:, 1:] - pos[:, list(sk.PARENTS[1:])], axis=-1)


def _check_reaches(gt, rec, tracking) -> None:
    """Tracked hands/feet within 1 cm of their target, plus what is out of the limb's reach."""
    g, p = gt.positions(), rec.positions()
    off = gt.skeleton.offsets
    for up, mid, end in LIMBS:
        if sk.JOINT_NAMES[end] not in tracking.joints:
            continue
        reach = np.linalg.norm(off[mid]) + np.linalg.norm(off[end])
        overshoot = np.maximum(0.0, np.linalg.norm(g[:, end] - p[:, up], axis=-1) - reach)
        err = np.linalg.norm(g[:, end] - p[:, end], axis=-1)
        assert (err <= overshoot + 0.01).all(), sk.JOINT_NAMES[end]


def test_registry():
    assert "ik" in available_methods()
    assert isinstance(get_method("ik", mode="offline", iterations=10), IKMethod)
    with pytest.raises(UserError, match="available: .*ik"):
        get_method("nope")
    register_method("ik-copy", IKMethod)
    assert "ik-copy" in available_methods()


def test_two_bone_reaches_and_bends_towards_pole():
    s, t = np.zeros(3), np.array([0.5, 0.0, 0.0])
    e = two_bone_mid(s, t, 0.3, 0.3, np.array([0.0, 0.0, -1.0]))
    assert np.linalg.norm(e - s) == pytest.approx(0.3) and np.linalg.norm(t - e) == pytest.approx(0.3)
    assert e[2] < 0  # towards the pole
    far = two_bone_mid(s, np.array([2.0, 0, 0]), 0.3, 0.3, np.array([0.0, 0, -1]))
    np.testing.assert_allclose(far, [0.3, 0, 0], atol=1e-3)  # straight towards the target


def test_full_preset_on_synthetic_clip(synthetic_motion):
    tr = simulate(synthetic_motion, "6")
    rec, results = run_method(get_method("ik"), tr, synthetic_motion.skeleton, progress=False)
    assert len(rec) == len(synthetic_motion) and len(results) == len(rec)
    pos = rec.positions()
    assert np.isfinite(pos).all() and np.isfinite(rec.local_rot).all()
    np.testing.assert_allclose(_bone_lengths(pos), _bone_lengths(synthetic_motion.positions()), atol=1e-9)
    np.testing.assert_allclose(pos[:, 0], synthetic_motion.root_pos, atol=1e-12)  # hip sensor
    _check_reaches(synthetic_motion, rec, tr)
    # 6-DoF sensors: hands, feet and head take the sensor's world rotation
    _, g_rot = rec.fk()
    for j in ("upperneck", "lwrist", "rankle"):
        k = tr.joints.index(j)
        assert np.degrees(Q.angle(g_rot[:, sk.JOINT_INDEX[j]], tr.rotations[:, k])).max() < 1e-4
    assert all(r.ms > 0 and r.iterations == 0 for r in results)


@pytest.mark.parametrize("preset", list(PRESETS))
def test_every_preset_gives_a_sane_pose(synthetic_motion, preset):
    clip = synthetic_motion.slice(0, 40)
    rec, _ = run_method(get_method("ik"), simulate(clip, preset), clip.skeleton, progress=False)
    pos = rec.positions()
    assert np.isfinite(pos).all()
    np.testing.assert_allclose(_bone_lengths(pos), _bone_lengths(clip.positions()), atol=1e-9)
    np.testing.assert_allclose(np.linalg.norm(rec.local_rot, axis=-1), 1.0, atol=1e-9)
    head = clip.positions()[:, sk.JOINT_INDEX["upperneck"]]
    assert np.linalg.norm(pos[:, sk.JOINT_INDEX["upperneck"]] - head, axis=-1).mean() < 0.25


def test_untracked_legs_hang_below_hips(synthetic_motion):
    clip = synthetic_motion.slice(0, 5)
    rec, _ = run_method(get_method("ik"), simulate(clip, "4"), clip.skeleton, progress=False)
    pos = rec.positions()
    for hip, ankle in ((1, 3), (5, 7)):
        horizontal = np.linalg.norm(pos[:, ankle, :2] - pos[:, hip, :2], axis=-1)
        assert horizontal.max() < 1e-6 and (pos[:, ankle, 2] < pos[:, hip, 2] - 0.7).all()


def test_lost_hand_keeps_its_last_pose(synthetic_motion):
    clip = synthetic_motion.slice(0, 30)
    tr = simulate(clip, "6")
    k = tr.joints.index("lwrist")
    tr.connected[10:, k] = False
    rec, _ = run_method(get_method("ik"), tr, clip.skeleton, progress=False)
    arm = [15, 16, 17]
    np.testing.assert_allclose(rec.local_rot[10:, arm], np.broadcast_to(rec.local_rot[9, arm], (20, 3, 4)))


def test_real_clip(shared_mocap):
    from engine.motion.retarget import load_motion

    path = next(iter(sorted((shared_mocap / "dragposer").rglob("*.bvh"))), None)
    if path is None:
        pytest.skip("no DragPoser clip in the shared data")
    clip = load_motion(path).slice(0, 120)
    tr = simulate(clip, "6")
    rec, _ = run_method(get_method("ik"), tr, clip.skeleton, progress=False)
    assert np.isfinite(rec.positions()).all()
    np.testing.assert_allclose(_bone_lengths(rec.positions()), _bone_lengths(clip.positions()), atol=1e-9)
    _check_reaches(clip, rec, tr)


def test_non_finite_and_absurd_readings_never_give_a_nan_pose(synthetic_motion):
    from engine.sensors import Sensor as SensorReading
    from engine.sensors import SensorFrame

    tracking = simulate(synthetic_motion, "6")
    ik = IKMethod()
    ik.reset(synthetic_motion.skeleton)
    first = ik.step(tracking.frame(0))
    frame = tracking.frame(1)
    bad = dict(frame.readings)
    bad["lwrist"] = SensorReading("lwrist", np.array([1e308, 0.0, 0.0]), bad["lwrist"].rotation, 6)
    bad["root"] = SensorReading("root", bad["root"].position, np.zeros(4), 6)  # zero hip quaternion
    res = ik.step(SensorFrame(frame.frame, bad))
    assert np.isfinite(res.positions).all() and np.isfinite(res.local_rot).all()
    assert any("lwrist" in w for w in res.warnings) and any("root" in w for w in res.warnings)
    assert np.linalg.norm(res.positions[0] - first.positions[0]) < 0.5, "the body stays where it was"
    nxt = ik.step(tracking.frame(2))  # and the next good frame is solved normally
    assert np.isfinite(nxt.positions).all()
