"""Pose mode keeps what the user did not drag: a head turn leaves the body, a hand put on
the hips bends no knee, a hand on a knee stoops standing, a reach to the floor crouches,
and the optional hold keeps the free arm. Drags are the pose-mode benchmark's own (``pose_tasks.drag`` on its task goals)."""

from __future__ import annotations

import numpy as np
import pytest

from engine import skeleton as sk
from engine.authoring.pose_mode import PoseMode, PoseOptions
from engine.authoring.pose_task_table import TASKS
from engine.authoring.pose_tasks import drag, resolve_goals

J = sk.JOINT_INDEX
TASK = {t.name: t for t in TASKS}


def _do(mode: PoseMode, name: str, events: int = 20) -> np.ndarray:
    """Do task ``name`` in ``mode``; returns the starting positions ``(22, 3)``."""
    start = mode.pose.positions.copy()
    offsets = mode.character.skeleton.offsets
    for g in resolve_goals(TASK[name], mode.pose, offsets, mode.heading):
        drag(mode, g, offsets, events)
    return start


def test_a_head_turn_leaves_the_body_where_it_was(vae):
    """The head turned 60 deg to the left (an Alt-drag) turns the head and moves no other
    joint by more than 5 mm; with the turn in the latent solve (``turn_weight=1``) the
    arms swing and the knees bend."""
    mode = PoseMode(vae)
    start = _do(mode, "head_turn")
    moved = np.linalg.norm(mode.pose.positions - start, axis=-1)
    assert moved.max() < 0.005, f"{sk.JOINT_NAMES[int(moved.argmax())]} moved {100 * moved.max():.1f} cm"
    turned = PoseMode(vae, options=PoseOptions(turn_weight=1.0))
    start = _do(turned, "head_turn")
    assert np.linalg.norm(turned.pose.positions - start, axis=-1).max() > 0.05


def test_hands_on_the_hips_bend_no_knee(vae):
    """Both wrists put on the iliac crests (within the standing arm's reach): the pelvis
    stays at its standing height (within 1 cm) and the knees where they were (2 cm);
    crouching for every downward drag (``crouch_below_reach=False``) lowers it by more
    than 5 cm."""
    mode = PoseMode(vae)
    start = _do(mode, "hands_on_hips")
    assert abs(mode.pose.root_pos[2] - start[0, 2]) < 0.01
    knees = [J["lknee"], J["rknee"]]
    assert np.linalg.norm(mode.pose.positions[knees] - start[knees], axis=-1).max() < 0.02
    for j in ("lwrist", "rwrist"):
        goal = resolve_goals(TASK["hands_on_hips"], PoseMode(vae).pose, mode.character.skeleton.offsets)
        assert np.linalg.norm(mode.pose.positions[J[j]] - next(g.position for g in goal if g.joint == j)) < 0.01
    always = PoseMode(vae, options=PoseOptions(crouch_below_reach=False))
    _do(always, "hands_on_hips")
    assert start[0, 2] - always.pose.root_pos[2] > 0.05


def test_a_hand_on_the_opposite_knee_stoops_standing(vae):
    """The right hand dragged to the left knee in one drag: the trunk bends forward over
    nearly straight legs, as a person reaches to a knee (the pelvis at most 12 cm lower,
    the trunk more than 55 deg from vertical), the hand arrives within 2 cm and both feet
    stay planted; a crouch for every reach below the hanging arm (``stoop_deg=0``) drops
    the pelvis more than 20 cm."""
    from engine.authoring.pose_metrics import check_pose

    mode = PoseMode(vae)
    start = _do(mode, "hand_to_knee")
    goal = start[J["lknee"]] + np.array([0.0, -0.08, 0.0])
    assert np.linalg.norm(mode.pose.positions[J["rwrist"]] - goal) < 0.02
    assert start[0, 2] - mode.pose.root_pos[2] < 0.12
    check = check_pose(mode.pose.local_rot, mode.pose.root_pos, mode.character.skeleton.offsets)
    assert check.trunk_tilt_deg > 55.0 and all(check.feet_down.values())
    ankles = [J["lankle"], J["rankle"]]
    assert np.linalg.norm(mode.pose.positions[ankles] - start[ankles], axis=-1).max() < 0.01
    crouched = PoseMode(vae, options=PoseOptions(stoop_deg=0.0, crouch_share=0.5))
    start = _do(crouched, "hand_to_knee")
    assert start[0, 2] - crouched.pose.root_pos[2] > 0.20


def test_a_reach_to_the_floor_still_crouches(vae):
    """The right hand to 10 cm above the floor in front of the toes lies below what the
    stooping trunk reaches: the knees bend (the pelvis more than 30 cm lower) and the hand
    arrives within 2 cm."""
    mode = PoseMode(vae)
    start = _do(mode, "pick_up")
    goal = resolve_goals(TASK["pick_up"], PoseMode(vae).pose, mode.character.skeleton.offsets)[0].position
    assert start[0, 2] - mode.pose.root_pos[2] > 0.30
    assert np.linalg.norm(mode.pose.positions[J["rwrist"]] - goal) < 0.02


def test_the_stooping_reach_lies_below_the_hanging_arm():
    """``arm_low_points``: without a stoop the arm hangs from the standing shoulder; a
    vertical trunk bent 90 deg puts the shoulder level with the hips, and the low point
    is continuous and falls as the stoop grows."""
    from engine.authoring.pose_root import arm_length, arm_low_points

    p = np.zeros((len(sk.JOINT_NAMES), 3))
    p[J["lhip"]], p[J["rhip"]] = [0.1, 0.0, 0.9], [-0.1, 0.0, 0.9]
    for s, x in (("l", 0.2), ("r", -0.2)):
        p[J[f"{s}shoulder"]], p[J[f"{s}elbow"]], p[J[f"{s}wrist"]] = [x, 0, 1.4], [x, 0, 1.1], [x, 0, 0.85]
    w = J["rwrist"]
    assert arm_length(p, w) == pytest.approx(0.55)
    lows = [arm_low_points(p, deg)[w] for deg in (0.0, 30.0, 60.0, 90.0)]
    assert lows[0] == pytest.approx(1.4 - 0.55)
    assert lows[3] == pytest.approx(0.9 - 0.55)
    assert lows[1] == pytest.approx(0.9 + 0.5 * np.cos(np.radians(30.0)) - 0.55)
    assert lows == sorted(lows, reverse=True)


@pytest.mark.parametrize("weight", [0.3])
def test_the_hold_keeps_the_free_arm_near_where_the_drag_began(vae, weight):
    """Dragging the left wrist 30 cm forward: with ``hold_weight`` the right wrist, which
    no target moves, stays nearer where it was than without; the held joints are all but
    the root, the targeted ones, the dragged arm's elbow and the planted feet."""

    def free_wrist_moved(hold: float) -> tuple[float, PoseMode]:
        mode = PoseMode(vae, options=PoseOptions(hold_weight=hold))
        start = mode.pose.positions.copy()
        for k in range(1, 21):
            mode.set_target("lwrist", start[J["lwrist"]] + np.array([0.0, -0.3, 0.0]) * k / 20)
            mode.solve()
        return float(np.linalg.norm(mode.pose.positions[J["rwrist"]] - start[J["rwrist"]])), mode

    held, mode = free_wrist_moved(weight)
    free, _ = free_wrist_moved(0.0)
    assert held < free - 0.005, (held, free)
    names = {sk.JOINT_NAMES[j] for j in mode.held()}
    assert {"rwrist", "relbow", "lknee", "upperneck", "chest"} <= names
    assert not names & {"root", "lwrist", "lelbow", "lankle", "ltoe", "rankle", "rtoe"}
    assert mode.anchor is not None and mode.anchor is not mode.pose


def test_a_reach_round_that_leaves_the_wrist_further_is_dropped(vae):
    """A wrist target out of reach takes further rounds; a round whose plain steps
    overshoot (here: a solve that returns the body further from the target) is not kept:
    the pose stays the one before it and no more rounds run."""
    mode = PoseMode(vae)
    w = mode.pose.positions[J["rwrist"]].copy()
    mode.set_target("rwrist", w + np.array([0.0, -0.25, -0.45]))
    solve, calls, poses = mode.character.solve, [], []

    def overshooting(*a, **k):
        calls.append(1)
        pose = solve(*a, **k)
        if len(calls) == 2:  # the first further round: the wrist ends 30 cm further off
            pose = pose.moved([0.0, 0.3, 0.3])
        poses.append(pose)
        return pose

    mode.character.solve = overshooting
    mode.solve()
    assert len(calls) == 2
    # the first round's pose, its planted toes put on their places
    np.testing.assert_array_equal(mode.pose.latent, poses[0].latent)
    feet = [J[j] for j in ("ltoe", "rtoe")]
    rest = [j for j in range(len(sk.JOINT_NAMES)) if j not in feet]
    np.testing.assert_allclose(mode.pose.positions[rest], poses[0].positions[rest], atol=1e-12)


#: Right-wrist drags from the neutral pose (character frame, metres) whose reach the
#: standing arm makes: forward, out to the side, up, overhead.
ARM_DRAGS = {
    "forward": (0.0, -0.30, 0.0),
    "out": (-0.30, 0.0, 0.0),
    "up": (0.0, -0.10, 0.40),
    "overhead": (-0.05, -0.05, 0.75),
}


def _drag_right_wrist(mode: PoseMode, offset, events: int = 20) -> np.ndarray:
    start = mode.pose.positions.copy()
    for k in range(1, events + 1):
        mode.set_target("rwrist", start[J["rwrist"]] + np.asarray(offset) * k / events)
        mode.solve()
    return start


@pytest.mark.parametrize("name", list(ARM_DRAGS))
def test_dragging_one_wrist_leaves_the_free_arm_hanging_as_it_was(vae, name):
    """The right wrist dragged within its reach: the left arm, which no target holds,
    does not swing (its wrist moves by less than 2 cm more than its shoulder, which goes
    where the body takes it), and where the trunk stays (up, overhead) the left wrist
    moves by less than 4 cm; the dragged wrist ends where it did without the hold
    (within 1 cm). Without the hold (``free_arm_weight=0``) the left arm swings 9-18 cm
    with the prior."""
    mode = PoseMode(vae)
    start = _drag_right_wrist(mode, ARM_DRAGS[name])
    p = mode.pose.positions
    wrist, shoulder = p[J["lwrist"]] - start[J["lwrist"]], p[J["lshoulder"]] - start[J["lshoulder"]]
    assert np.linalg.norm(wrist - shoulder) < 0.02, f"left arm swung {100 * np.linalg.norm(wrist - shoulder):.1f} cm"
    if name in ("up", "overhead"):
        assert np.linalg.norm(wrist) < 0.04, f"left wrist moved {100 * np.linalg.norm(wrist):.1f} cm"
    free = PoseMode(vae, options=PoseOptions(free_arm_weight=0.0))
    _drag_right_wrist(free, ARM_DRAGS[name])
    goal = start[J["rwrist"]] + np.asarray(ARM_DRAGS[name])
    held_err = np.linalg.norm(p[J["rwrist"]] - goal)
    free_err = np.linalg.norm(free.pose.positions[J["rwrist"]] - goal)
    assert held_err < free_err + 0.01, (held_err, free_err)


@pytest.mark.parametrize("name", ["hand_to_knee", "squat"])
def test_a_settle_keeps_the_planted_feet_toes_included(vae, name):
    """Edit > Settle pose after the hand-to-knee reach (or the squat): both feet stay
    where they were planted, the toe joints within 1 cm (the settle's grounded solve left
    a toe 4.2 cm off, the foot rolled on its ankle), the ankles within 1 mm."""
    mode = PoseMode(vae)
    start = _do(mode, name)
    mode.settle()
    p = mode.pose.positions
    for j in ("ltoe", "rtoe"):
        assert np.linalg.norm(p[J[j]] - start[J[j]]) < 0.01, (
            f"{j} moved {100 * np.linalg.norm(p[J[j]] - start[J[j]]):.1f} cm"
        )
    for j in ("lankle", "rankle"):
        assert np.linalg.norm(p[J[j]] - start[J[j]]) < 0.001


@pytest.mark.parametrize(
    "move", [(0.0, -0.3, -0.4), (0.5, 0.0, 0.0), (0.0, 0.0, 0.4)], ids=["forward_down", "out", "up"]
)
def test_a_drag_of_a_wrist_keeps_the_planted_toes_on_every_event(vae, move):
    """The feet no target moves stay planted toe and all while a wrist is dragged: on
    every drag event both toe joints lie within 3 mm of their planted places. Left to the
    latent (a soft target), a toe moved up to 2.5 cm in the reach forward and down, the
    foot rolled on its planted ankle."""
    m = PoseMode(vae, 1.87)
    planted = {j: m.planted[j].copy() for j in ("ltoe", "rtoe")}
    start = m.pose.positions[J["lwrist"]].copy()
    worst = 0.0
    for k in range(1, 21):
        m.set_target("lwrist", start + np.array(move) * k / 20)
        m.solve()
        worst = max(worst, *(np.linalg.norm(m.pose.positions[J[j]] - p) for j, p in planted.items()))
    assert worst < 0.003, f"a planted toe moved {100 * worst:.2f} cm"
