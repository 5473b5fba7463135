"""A 3-DoF foot tracker's ankle levelled along the pelvis heading after the solve
(setting ``level_feet``, engine.solver.limb_ik.finish's ``level``)."""

from __future__ import annotations

import numpy as np
import pytest

from engine import skeleton as sk
from engine.constraints import PinConstraint
from engine.kinematics import quat_np as QN
from engine.kinematics import quaternion as Q
from engine.kinematics.fk import fk, fk_joints
from engine.methods.dragposer import DragPoserMethod
from engine.solver import limb_ik
from engine.tracking import simulate
from tests.engine.test_head_reach import clip  # noqa: F401  (the fixture)
from tests.engine.test_optimizer_standins import CountingPredictor, MLPDecoder

J = sk.JOINT_INDEX
ANKLES = (J["lankle"], J["rankle"])


@pytest.mark.parametrize("seed", range(4))
def test_a_levelled_ankle_takes_the_root_s_yaw_and_no_joint_above_it_moves(seed):
    rng = np.random.default_rng(seed)
    local = Q.normalize(np.array([1.0, 0, 0, 0]) + rng.normal(0, 0.3, size=(sk.NUM_JOINTS, 4)))
    root, off = np.array([0.1, -0.2, 0.95]), sk.Skeleton.canonical().offsets
    before, _ = fk(local, root, off)
    out, pos = limb_ik.finish(local, root, off, {}, {}, level=ANKLES)
    _, rots = fk_joints(out, root, off, list(ANKLES))
    want = QN.heading(np.asarray(local[0], dtype=np.float64))
    for r in rots:
        assert min(np.abs(r - want).max(), np.abs(r + want).max()) < 1e-9  # yaw only: no pitch or roll
    toes = [J["ltoe"], J["rtoe"]]
    np.testing.assert_allclose(np.delete(pos, toes, axis=0), np.delete(before, toes, axis=0), atol=1e-9)
    # the feet keep their rest shape turned by the heading alone
    for a, t in zip(ANKLES, toes):
        np.testing.assert_allclose(pos[t] - pos[a], QN.rotate(want, off[t]), atol=1e-9)
    # a 6-DoF tracker's rotation wins over the rule for the same joint
    tracked = np.array([0.7, 0.3, -0.2, 0.6]) / np.linalg.norm([0.7, 0.3, -0.2, 0.6])
    out2, _ = limb_ik.finish(local, root, off, {}, {ANKLES[0]: tracked}, level=ANKLES)
    _, (r0,) = fk_joints(out2, root, off, [ANKLES[0]])
    assert min(np.abs(r0 - tracked).max(), np.abs(r0 + tracked).max()) < 1e-9


def test_position_only_feet_are_levelled_unless_a_user_constraint_holds_the_foot(clip):  # noqa: F811
    tr = simulate(clip, "6x3dof")
    m = DragPoserMethod(
        MLPDecoder(), CountingPredictor(), iterations=3, max_iterations=20, level_feet=True, tuning="off"
    )
    m.reset(clip.skeleton)
    res = m.step(tr.frame(0))
    _, rots = fk_joints(res.local_rot, res.root_pos, clip.skeleton.offsets, list(ANKLES))
    want = QN.heading(np.asarray(res.local_rot[0], dtype=np.float64))
    for r in rots:  # the result's rotations are float32's
        assert min(np.abs(r - want).max(), np.abs(r + want).max()) < 1e-5
    assert set(m.plan(tr.frame(1)).level) == set(ANKLES)
    for joint, kept in (("ltoe", {J["rankle"]}), ("rankle", {J["lankle"]}), ("lwrist", set(ANKLES))):
        m = DragPoserMethod(
            MLPDecoder(), CountingPredictor(), iterations=3, max_iterations=20, level_feet=True, tuning="off"
        )
        m.add_constraint(PinConstraint(name="pin", joint=joint))
        m.reset(clip.skeleton)
        m.step(tr.frame(0))
        assert set(m.plan(tr.frame(1)).level) == kept, f"a user's constraint on {joint}"
    # 6-DoF feet give their own rotation: nothing to level
    m = DragPoserMethod(
        MLPDecoder(), CountingPredictor(), iterations=3, max_iterations=20, level_feet=True, tuning="off"
    )
    m.reset(clip.skeleton)
    six = simulate(clip, "6")
    m.step(six.frame(0))
    assert m.plan(six.frame(1)).level == ()


@pytest.mark.parametrize(
    ("preset", "expected"), [("6x3dof", True), ("6", False), ("4", False), ("3-head-hands", False)]
)
def test_only_the_position_only_profile_levels_the_feet(preset, expected):
    from engine.solver import OptimizerSettings
    from engine.solver.profiles import effective
    from engine.tracking.presets import PRESET_SENSORS

    joints = [s.joint for s in PRESET_SENSORS[preset]]
    hip = all(s.dof == 6 for s in PRESET_SENSORS[preset] if s.joint == "root")
    assert effective(OptimizerSettings(), joints, explicit=(), hip_rotation=hip).level_feet is expected
