"""Tracker simulation: readings match FK, and the failure models match their definitions."""

from __future__ import annotations

import numpy as np
import pytest

from engine import skeleton as sk
from engine.kinematics import quaternion as Q
from engine.motion.clip import Motion
from engine.tracking import simulate
from engine.tracking.simulate import FAULTY_DOWN_FRAMES, faulty_mask, gap_mask


def _still(frames: int) -> Motion:
    rot = np.zeros((frames, sk.NUM_JOINTS, 4))
    rot[..., 0] = 1
    return Motion(rot, np.tile([0.0, 0.0, 0.95], (frames, 1)))


def _runs(mask: np.ndarray) -> list[tuple[int, int]]:
    """(start, length) of every run of False in a 1-D mask."""
    d = np.diff(np.concatenate([[1], mask.astype(int), [1]]))
    starts, ends = np.flatnonzero(d == -1), np.flatnonzero(d == 1)
    return list(zip(starts.tolist(), (ends - starts).tolist()))


def test_clean_readings_are_fk(synthetic_motion):
    tr = simulate(synthetic_motion, "6")
    pos, rot = synthetic_motion.fk()
    idx = [sk.JOINT_INDEX[j] for j in tr.joints]
    np.testing.assert_allclose(tr.positions, pos[:, idx], atol=1e-12)
    assert np.all(np.degrees(Q.angle(tr.rotations, rot[:, idx])) < 1e-5)
    assert tr.connected.all() and len(tr) == len(synthetic_motion)
    fr = tr.frame(10)
    assert fr.frame == 10 and set(fr.readings) == set(tr.joints)
    np.testing.assert_allclose(fr.readings["lwrist"].position, pos[10, sk.JOINT_INDEX["lwrist"]])


def test_position_only_sensors_hide_rotation(synthetic_motion):
    tr = simulate(synthetic_motion, "6x3dof")
    assert tr.dof == (3,) * 6
    np.testing.assert_allclose(tr.rotations, np.broadcast_to([1.0, 0, 0, 0], tr.rotations.shape))
    assert tr.frame(0).readings["root"].dof == 3


def test_noise_statistics_and_determinism():
    m = _still(4000)
    a = simulate(m, "6", noise_pos_m=0.01, noise_rot_deg=2.0, seed=3)
    b = simulate(m, "6", noise_pos_m=0.01, noise_rot_deg=2.0, seed=3)
    np.testing.assert_array_equal(a.positions, b.positions)
    clean = simulate(m, "6")
    err = a.positions - clean.positions
    assert abs(err.std() - 0.01) < 0.0005 and abs(err.mean()) < 0.0005
    ang = np.degrees(Q.angle(a.rotations, clean.rotations))
    # rotation vector with N(0, s^2) components: E|v|^2 = 3 s^2
    assert abs(np.sqrt((ang**2).mean()) - 2.0 * np.sqrt(3)) < 0.1
    c = simulate(m, "6", noise_pos_m=0.01, seed=4)
    assert not np.array_equal(a.positions, c.positions)


def test_faulty_matches_dragposer_definition():
    frames, p = 200_000, 0.01
    rng = np.random.default_rng(0)
    conn = faulty_mask(frames, 6, p, rng)
    runs = [r for s in range(6) for r in _runs(conn[:, s])]
    full = [n for start, n in runs if start + n < frames]
    assert full and all(n == FAULTY_DOWN_FRAMES for n in full)  # back after 100 frames
    # one failure per frame with probability p (always some sensor is up with 6 sensors)
    expected = frames * p
    assert abs(len(runs) - expected) < 4 * np.sqrt(expected)
    # never more than one sensor fails on the same frame
    starts = np.diff(np.concatenate([np.ones((1, 6), bool), conn]).astype(int), axis=0) == -1
    assert starts.sum(axis=1).max() == 1


def test_faulty_only_picks_connected_sensors():
    conn = faulty_mask(5000, 1, 0.5, np.random.default_rng(1))
    runs = _runs(conn[:, 0])
    # with one sensor, a failure while it is down is skipped: runs never merge
    assert all(n == FAULTY_DOWN_FRAMES for s, n in runs if s + n < 5000)


def test_gaps_match_rpm_definition():
    fps, frames = 60.0, 400_000
    conn = gap_mask(frames, fps, np.random.default_rng(0))
    runs = _runs(conn)
    lengths = np.array([n for s, n in runs if s + n < frames])
    assert lengths.min() >= 30 and lengths.max() <= 120  # 0.5 .. 2 s
    assert abs(lengths.mean() - 75) < 3  # U(0.5, 2) s -> mean 1.25 s
    starts = np.array([s for s, _ in runs])
    ends = starts[:-1] + lengths[: len(starts) - 1]
    assert (starts[1:] - ends).min() >= 120  # >= 2 s apart
    assert starts[0] >= 60  # warm-up second stays tracked
    # a gap starts with probability 2.5 % on every frame where one may start
    eligible = frames - 60 - sum(n + 120 for _, n in runs)
    rate = len(runs) / eligible
    assert abs(rate - 0.025) < 0.002


def test_gaps_only_hit_hands_and_are_seeded():
    m = _still(3000)
    tr = simulate(m, "6", gaps=True, seed=5)
    lost = ~tr.connected
    hands = [tr.joints.index("lwrist"), tr.joints.index("rwrist")]
    others = [k for k in range(6) if k not in hands]
    assert lost[:, hands].any(axis=0).all() and not lost[:, others].any()
    assert not np.array_equal(tr.connected[:, hands[0]], tr.connected[:, hands[1]])  # independent
    again = simulate(m, "6", gaps=True, seed=5)
    np.testing.assert_array_equal(tr.connected, again.connected)
    assert not simulate(m, "3-hip-hands", gaps=False).connected.__invert__().any()


def test_lost_sensor_holds_last_reading(synthetic_motion):
    tr = simulate(synthetic_motion, "6", faulty=0.2, seed=2)
    clean = simulate(synthetic_motion, "6")
    f, s = np.argwhere(~tr.connected)[0]
    assert f > 0
    np.testing.assert_allclose(tr.positions[f, s], clean.positions[f - 1, s])
    kinds = {k for _, _, k in tr.transitions()}
    assert False in kinds
    frame, sensor, reconnected = tr.transitions()[0]
    assert (frame, sensor, reconnected) == (f, s, False)


def test_unknown_sensor_fails_early(synthetic_motion):
    from engine.errors import UserError

    with pytest.raises(UserError, match="valid presets"):
        simulate(synthetic_motion, "7")
    tr = simulate(synthetic_motion, ["root", "lwrist"])  # the studio passes joint lists
    assert tr.joints == ("root", "lwrist")
