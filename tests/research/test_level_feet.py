"""research/level_feet.py: each rule's ankle rotations, and the wrapped finish levels
the ankles the rule says and moves no joint above them."""

from __future__ import annotations

import numpy as np

from engine import skeleton as sk
from engine.kinematics import quat_np as QN
from engine.kinematics import quaternion as Q
from engine.kinematics.fk import fk, fk_joints
from engine.solver import limb_ik

from .script_loader import load_script


def _pose(seed: int):
    rng = np.random.default_rng(seed)
    local = Q.normalize(np.array([1.0, 0, 0, 0]) + rng.normal(0, 0.3, size=(sk.NUM_JOINTS, 4)))
    return local, np.array([0.0, 0.1, 0.9]), sk.Skeleton.canonical().offsets


def _same(a, b) -> bool:
    return min(np.abs(a - b).max(), np.abs(a + b).max()) < 1e-9


def test_each_rule_gives_the_ankles_what_it_says():
    lf = load_script("level_feet")
    local, root, off = _pose(0)
    _, own = fk_joints(local, root, off, list(lf.ANKLES))
    yaw = QN.heading(local[0])
    flat, turn = (lf.ankle_targets(local, root, off, r) for r in ("flat", "turn"))
    for k, j in enumerate(lf.ANKLES):
        assert _same(flat[j], QN.heading(own[k]))
        assert _same(QN.heading(turn[j]), yaw)  # turned to the pelvis's yaw...
        # ...keeping the pitch and roll: the same rotation in the foot's own yaw frame
        assert _same(QN.mul(QN.conjugate(yaw), turn[j]), QN.mul(QN.conjugate(QN.heading(own[k])), own[k]))


def test_the_wrapped_finish_flattens_the_ankles_and_moves_nothing_above_them():
    lf = load_script("level_feet")
    local, root, off = _pose(1)
    wrapped = lf.with_rule(limb_ik.finish, "flat")
    out, pos = wrapped(local, root, off, {}, {})
    before, _ = fk(local, root, off)
    toes = [sk.JOINT_INDEX["ltoe"], sk.JOINT_INDEX["rtoe"]]
    np.testing.assert_allclose(np.delete(pos, toes, 0), np.delete(before, toes, 0), atol=1e-9)
    _, own = fk_joints(local, root, off, list(lf.ANKLES))
    _, rots = fk_joints(out, root, off, list(lf.ANKLES))
    assert all(_same(r, QN.heading(o)) for r, o in zip(rots, own))
