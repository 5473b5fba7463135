"""Pose mode's trunk rule (``PoseOptions.keep_trunk``, :mod:`engine.authoring.pose_trunk`):
the arms dragged overhead leave the trunk's lean as it stood, a low reach still bends
it forward, and a target on the trunk or a leg leaves the trunk to the user."""

from __future__ import annotations

import numpy as np

from engine import skeleton as sk
from engine.authoring.character import Pose
from engine.authoring.pose_metrics import trunk_tilt_deg
from engine.authoring.pose_mode import PoseMode, PoseOptions
from engine.authoring.pose_task_table import TASKS
from engine.authoring.pose_tasks import drag, resolve_goals
from engine.authoring.pose_trunk import BONES, keep_trunk, unleaned
from engine.kinematics import quat_np as QN
from engine.kinematics.fk import fk

J = sk.JOINT_INDEX
TASK = {t.name: t for t in TASKS}
#: The character faces -Y (heading 0).
FORWARD = np.array([0.0, -1.0, 0.0])
KEEP = PoseOptions(keep_trunk=True)


def _do(mode: PoseMode, name: str, events: int = 20) -> tuple[np.ndarray, list]:
    """Do task ``name`` in ``mode`` as the benchmark does; the starting positions ``(22, 3)``
    and the goals."""
    start = mode.pose.positions.copy()
    offsets = mode.character.skeleton.offsets
    goals = resolve_goals(TASK[name], mode.pose, offsets, mode.heading)
    for g in goals:
        drag(mode, g, offsets, events)
    return start, goals


def _neck_forward(positions: np.ndarray) -> float:
    """How far (metres) the head joint is in front of the pelvis."""
    return float((positions[J["upperneck"]] - positions[J["root"]]) @ FORWARD)


def test_unleaned_undoes_only_a_lean_back():
    start = np.array([0.0, -0.2, 1.0]) / np.linalg.norm([0.0, -0.2, 1.0])
    back = np.array([0.3, 0.1, 1.0]) / np.linalg.norm([0.3, 0.1, 1.0])
    kept = unleaned(back, start, FORWARD)
    assert np.isclose(np.linalg.norm(kept), 1.0)
    assert kept @ FORWARD >= start @ FORWARD - 1e-12  # leans back no further than at the start
    assert kept[0] > 0.2  # the side lean stays
    ahead = np.array([0.0, -0.6, 0.8])
    assert np.array_equal(unleaned(ahead, start, FORWARD), ahead)  # a forward bend stays


def test_keep_trunk_turns_a_leaned_back_spine_forward_and_keeps_the_wrists(vae):
    """The mean pose with its lower back turned 25 deg backwards: after the rule no trunk
    bone leans further back than in the mean pose, and a wrist given as a reach target
    is on it."""
    mode = PoseMode(vae)
    offsets = mode.character.skeleton.offsets
    start = mode.pose
    local = start.local_rot.copy()
    local[J["lowerback"]] = QN.mul(
        QN.from_axis_angle(np.array([1.0, 0.0, 0.0]), np.radians(-25.0)), local[J["lowerback"]]
    )
    positions = fk(local, start.root_pos, offsets)[0]
    leaned = Pose(start.latent, local, start.root_pos.copy(), positions)
    assert _neck_forward(positions) < _neck_forward(start.positions) - 0.1
    wrist = start.positions[J["lwrist"]] + np.array([0.0, -0.1, 0.3])
    kept = keep_trunk(leaned, start, FORWARD, offsets, {J["lwrist"]: wrist}, {})
    for j, end in BONES:
        have = kept.positions[end] - kept.positions[j]
        was = start.positions[end] - start.positions[j]
        assert have @ FORWARD / np.linalg.norm(have) >= was @ FORWARD / np.linalg.norm(was) - 1e-6, sk.JOINT_NAMES[j]
    assert np.linalg.norm(kept.positions[J["lwrist"]] - wrist) < 1e-6
    assert abs(_neck_forward(kept.positions) - _neck_forward(start.positions)) < 0.02


def test_hands_dragged_overhead_leave_the_trunk_upright(vae):
    """Both wrists dragged overhead (the benchmark's task): the trunk tilt stays within 2
    deg of the starting pose's and the head joint within 2 cm of where it stood in front
    of the pelvis, with both wrists on their goals; without the rule the latent leans the
    trunk back (the head joint 10 cm or more behind; the option is off by default)."""
    mode = PoseMode(vae, options=KEEP)
    start, goals = _do(mode, "hands_overhead")
    assert abs(trunk_tilt_deg(mode.pose.positions) - trunk_tilt_deg(start)) < 2.0
    assert _neck_forward(mode.pose.positions) > _neck_forward(start) - 0.02
    for g in goals:
        assert np.linalg.norm(mode.pose.positions[J[g.joint]] - g.position) < 1e-3, g.joint
    free = PoseMode(vae)
    start, _ = _do(free, "hands_overhead")
    assert _neck_forward(free.pose.positions) < _neck_forward(start) - 0.10


def test_a_low_reach_still_bends_the_trunk_forward(vae):
    """The right hand to the left knee: the trunk bends forward (30 deg or more) as
    without the rule, and the hand arrives within 2 cm."""
    mode = PoseMode(vae, options=KEEP)
    start, goals = _do(mode, "hand_to_knee", events=10)
    assert trunk_tilt_deg(mode.pose.positions) > 30.0
    assert _neck_forward(mode.pose.positions) > _neck_forward(start) + 0.1
    assert np.linalg.norm(mode.pose.positions[J["rwrist"]] - goals[0].position) < 0.02


def test_a_trunk_or_leg_target_leaves_the_trunk_to_the_user(vae):
    """The head joint dragged 12 cm backwards goes back (the rule does not undo what the
    user drags); a step forward (an ankle target) poses as without the rule."""
    mode = PoseMode(vae, options=KEEP)
    start = mode.pose.positions.copy()
    for k in range(1, 11):
        mode.set_target("upperneck", start[J["upperneck"]] - FORWARD * 0.12 * k / 10)
        mode.solve()
    assert _neck_forward(mode.pose.positions) < _neck_forward(start) - 0.06
    kept, free = PoseMode(vae, options=KEEP), PoseMode(vae)
    _do(kept, "step_forward", events=10)
    _do(free, "step_forward", events=10)
    assert np.array_equal(kept.pose.positions, free.pose.positions)
