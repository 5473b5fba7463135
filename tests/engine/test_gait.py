"""The gait planner (engine/solver/gait.py) and DragPoser's ``gait`` term: a travelling
head makes the feet alternate and plant; a still one leaves the term off. The term's
residual, Jacobian and paths are checked by the generic registry tests (its ``examples``)."""

from __future__ import annotations

import numpy as np
import pytest
import torch

from engine import skeleton as sk
from engine.constraints.gait import ANKLES, GaitTargets
from engine.methods.dragposer import DragPoserMethod
from engine.motion.clip import Motion
from engine.solver.gait import GaitParams, GaitPlanner
from engine.tracking import simulate
from tests.engine.test_optimizer_standins import CountingPredictor, MLPDecoder

FPS = 60.0
ROOT, HEAD = sk.JOINT_INDEX["root"], sk.JOINT_INDEX["upperneck"]


def walk(planner: GaitPlanner, frames: int, speed: float, arms: bool) -> list[GaitTargets]:
    """Drive ``planner`` with a head walking along -Y at ``speed`` m/s (hands swinging in
    opposition at 1 stride per second when ``arms``), the solver standing in as perfect:
    each frame's ankles are where the previous frame's targets put them."""
    pose = sk.Skeleton.canonical().rest_positions()
    pose -= pose[ROOT] - [0.0, 0.0, 0.95]
    ankles = pose[list(ANKLES)].copy()
    out: list[GaitTargets] = []
    for i in range(frames):
        t = i / FPS
        shift = np.array([0.0, -speed * t, 0.0])
        previous = pose + shift
        if out:  # the ankles the last targets asked for (the others ride along with the body)
            last = out[-1]
            ankles = np.where(last.scale > 0, last.target, ankles + [0.0, -speed / FPS, 0.0])
        previous[list(ANKLES)] = ankles
        swing = 0.25 * np.sin(2.0 * np.pi * t) if arms else 0.0  # left hand forward (-Y) when > 0
        hands = np.array([[0.2, -swing, 1.0], [-0.2, swing, 1.0]]) + shift
        out.append(planner.update(previous[HEAD], previous, hands))
    return out


@pytest.mark.parametrize("arms", [True, False])
def test_walking_head_makes_the_feet_alternate_and_plant(arms):
    targets = walk(GaitPlanner(FPS), 240, 1.2, arms)
    stance = np.array([-1 if not t.active else t.stance for t in targets])
    on = stance >= 0
    assert on[60:].all()  # on once the velocity window is full and the speed is up
    changes = np.flatnonzero(np.diff(stance[on]) != 0)
    assert len(changes) >= 5 and set(stance[on]) == {0, 1}  # about 2 steps per second
    # the stance foot's target stays put for its whole stance; the swing foot's moves ahead (-Y)
    runs = np.split(np.arange(on.sum()), changes + 1)
    onf = np.flatnonzero(on)
    settled = int(np.ceil(GaitParams().settle_s * FPS))  # frames a landed foot's target glides
    for run in runs[1:-1]:
        frames = onf[run]
        k = stance[frames[0]]
        planted = np.array([targets[f].target[k] for f in frames[settled:]])
        assert np.ptp(planted, axis=0).max() < 1e-12
        swing = np.array([targets[f].target[1 - k, 1] for f in frames])
        assert swing[-1] < swing[0] - 0.2
    if arms:  # the arms say which foot stands: left while the left hand moves forward
        rate = np.cos(2.0 * np.pi * np.arange(240) / FPS)  # d/dt of the left-minus-right forward offset
        agree = np.mean((stance[on] == 0) == (rate[on] > 0))
        assert agree > 0.8


@pytest.mark.parametrize("arms", [True, False])
@pytest.mark.parametrize("speed", [0.8, 1.2, 1.6])
def test_the_targets_and_weights_do_not_jump_when_the_feet_swap(arms, speed):
    """The arms swap the feet before the swing target reaches its landing spot: the landed
    foot's target glides on from the swing target's last position, and the weights trade places
    over a few frames, so neither steps at a swap (a step is a jerk in the solved legs)."""
    targets = walk(GaitPlanner(FPS), 240, speed, arms)
    stance = np.array([-1 if not t.active else t.stance for t in targets])
    swaps = [i for i in range(61, 240) if stance[i - 1] >= 0 and stance[i] >= 0 and stance[i] != stance[i - 1]]
    assert len(swaps) >= 4
    p = GaitParams()
    for i in swaps:
        jump = np.linalg.norm(targets[i].target[:, :2] - targets[i - 1].target[:, :2], axis=-1)
        assert jump.max() < 0.02, (i, jump)  # the body travels 1.3-2.7 cm a frame
        weight = targets[i].scale[:, 0] ** 2
        before = targets[i - 1].scale[:, 0] ** 2
        assert np.abs(weight - before).max() < 0.5 * (p.stance_weight - p.swing_weight)
    # the landed foot reaches its landing spot and stays there for the rest of its stance
    i = swaps[1]
    k = stance[i]
    later = [targets[f].target[k] for f in range(i + int(np.ceil(p.settle_s * FPS)), swaps[2])]
    assert np.ptp(np.array(later), axis=0).max() < 1e-12


def test_a_still_head_leaves_the_term_off():
    targets = walk(GaitPlanner(FPS), 120, 0.0, arms=True)
    assert not any(t.active for t in targets)
    slow = walk(GaitPlanner(FPS), 120, 0.9 * GaitParams().on_speed, arms=True)
    assert not any(t.active for t in slow)


def test_a_run_leaves_the_term_off_and_a_fast_walk_on():
    params = GaitParams()
    run = walk(GaitPlanner(FPS), 120, 1.1 * params.stop_speed, arms=True)
    assert not any(t.active for t in run)
    brisk = walk(GaitPlanner(FPS), 120, 0.95 * params.run_speed, arms=True)
    assert all(t.active for t in brisk[60:])
    assert params.activity(0.5 * (params.run_speed + params.stop_speed)) == pytest.approx(0.5)


def test_no_anchor_or_first_frame_is_off():
    p = GaitPlanner(FPS)
    assert not p.update(None, np.zeros((22, 3))).active
    assert not p.update(np.zeros(3), None).active


def _clip(speed: float, frames: int = 90) -> Motion:
    t = np.arange(frames) / FPS
    rot = np.tile(np.array([1.0, 0.0, 0.0, 0.0]), (frames, 22, 1))
    return Motion(rot, np.stack([0 * t, -speed * t, 1.0 + 0 * t], -1))


@pytest.mark.parametrize("speed, active", [(1.2, True), (0.0, False)])
def test_dragposer_adds_the_gait_term_while_the_head_travels(speed, active):
    torch.manual_seed(0)
    m = DragPoserMethod(MLPDecoder(), CountingPredictor(), iterations=2, max_iterations=5, gait_weight=3.0)
    clip = _clip(speed)
    tr = simulate(clip, "3-head-hands")
    m.reset(clip.skeleton)
    out = [m.step(tr.frame(i)) for i in range(len(clip))]
    assert all(np.isfinite(r.positions).all() for r in out)
    # the term is in the solve; it pulls only while the head travels
    assert "gait" in out[-1].losses[0]
    assert (out[-1].losses[0]["gait"] > 0) == active and m.gait.targets.active == active


def test_gait_weight_zero_turns_the_term_off():
    clip = _clip(1.2, 40)
    tr = simulate(clip, "3-head-hands")
    torch.manual_seed(0)
    m = DragPoserMethod(MLPDecoder(), CountingPredictor(), iterations=2, max_iterations=5, gait_weight=0.0)
    m.reset(clip.skeleton)
    out = [m.step(tr.frame(i)) for i in range(len(clip))]
    assert "gait" not in out[-1].losses[0] and not m.gait.targets.active


@pytest.mark.parametrize("preset, steps", [("3-head-hands", True), ("4", False)])
def test_the_head_profile_plants_the_feet_and_the_hip_profile_does_not(preset, steps):
    clip = _clip(1.2, 60)
    tr = simulate(clip, preset)
    torch.manual_seed(0)
    m = DragPoserMethod(MLPDecoder(), CountingPredictor(), iterations=2, max_iterations=5)
    m.reset(clip.skeleton)
    out = [m.step(tr.frame(i)) for i in range(len(clip))]
    # the hip profile has the term for its standing legs, which are off at a 1.2 m/s walk
    assert "gait" in out[-1].losses[0]
    assert m.gait.targets.active == steps and (m.gait.targets.stance is not None) == steps


def _standing_pose() -> np.ndarray:
    pose = sk.Skeleton.canonical().rest_positions()
    pose -= pose[ROOT] - [0.0, 0.0, 0.95]
    pose[list(ANKLES), 0] += [0.12, -0.12]  # feet wide apart: the ankles 12 cm outside their hips
    return pose


def test_standing_legs_pull_each_ankle_under_its_hip_while_the_body_stands():
    pose = _standing_pose()
    hips = pose[[sk.JOINT_INDEX["lhip"], sk.JOINT_INDEX["rhip"]]]
    planner = GaitPlanner(FPS)
    for _ in range(3):
        t = planner.update(pose[ROOT], pose, walk=False, stand=2.0)
    assert t.active and t.stance is None  # a pull, not a step
    np.testing.assert_allclose(t.target[:, :2], hips[:, :2])
    np.testing.assert_allclose(t.scale[:, :2], np.sqrt(2.0))
    assert np.all(t.scale[:, 2] == 0.0)  # heights stay the ground term's


@pytest.mark.parametrize("speed, share", [(0.3, 1.0), (0.9, 0.5), (1.5, 0.0)])
def test_standing_legs_fade_out_with_speed(speed, share):
    pose = _standing_pose()
    planner = GaitPlanner(FPS)
    for i in range(30):
        t = planner.update(pose[ROOT] + [0.0, -speed * i / FPS, 0.0], pose, walk=False, stand=1.0)
    assert GaitParams().standing(speed) == pytest.approx(share)
    np.testing.assert_allclose(t.scale[:, :2] ** 2, share, atol=1e-9)


@pytest.mark.parametrize("distance, share", [(None, 1.0), (1.5, 0.0), (2.5, 0.5), (3.5, 1.0)])
def test_standing_legs_leave_familiar_readings_to_the_pose_bank(distance, share):
    """Readings near the bank's (CMU-like motion) keep the bank's legs; far ones get the pull."""
    pose = _standing_pose()
    planner = GaitPlanner(FPS)
    for _ in range(3):
        t = planner.update(pose[ROOT], pose, walk=False, stand=1.0, distance=distance)
    np.testing.assert_allclose(t.scale[:, :2] ** 2, share, atol=1e-9)
    assert t.active == (share > 0)


def test_standing_legs_and_steps_sum_as_one_pull():
    """Where the steps and the standing pull both act, an ankle's target is their
    weighted mean and its weight their sum: the same loss as the two pulls apart."""
    pose = _standing_pose()
    hips = pose[[sk.JOINT_INDEX["lhip"], sk.JOINT_INDEX["rhip"]]][:, :2]
    a, b = GaitPlanner(FPS), GaitPlanner(FPS)
    for i in range(40):  # 0.8 m/s: steps on (activity 1), standing pull at its fade's middle
        anchor = pose[ROOT] + [0.0, -0.8 * i / FPS, 0.0]
        steps = a.update(anchor, pose)
        both = b.update(anchor, pose, stand=1.0)
    w = GaitParams().standing(0.8)
    assert 0.0 < w < 1.0 and steps.active
    x = np.random.default_rng(0).normal(size=(2, 2))
    loss_apart = np.sum((steps.scale[:, :2] * (x - steps.target[:, :2])) ** 2) + w * np.sum((x - hips) ** 2)
    loss_one = np.sum((both.scale[:, :2] * (x - both.target[:, :2])) ** 2)
    # equal up to a constant in x: compare their gradients
    g_apart = 2 * steps.scale[:, :2] ** 2 * (x - steps.target[:, :2]) + 2 * w * (x - hips)
    g_one = 2 * both.scale[:, :2] ** 2 * (x - both.target[:, :2])
    np.testing.assert_allclose(g_one, g_apart, atol=1e-12)
    assert loss_one <= loss_apart + 1e-12


@pytest.mark.shared_data
def test_standing_legs_bring_a_standing_performers_legs_nearer_the_truth(shared_mocap):
    """Frames 240-390 of a DanceDB take, where the performer sways on the spot (hips at
    0.0-0.4 m/s) and the pose bank's guess lifts and bends the legs 15-20 cm off the truth:
    preset 4 with the shipped models, the hip profile's standing legs against none."""
    from engine.kinematics.fk import fk
    from engine.methods import get_method, run_method
    from engine.motion.retarget import load_motion

    motion = load_motion(shared_mocap / "dragposer" / "example.bvh", max_frames=390).slice(240)
    tracking = simulate(motion, "4")
    truth = fk(motion.local_rot, motion.root_pos, motion.skeleton.offsets)[0]
    legs = [sk.JOINT_INDEX[n] for n in ("lknee", "lankle", "ltoe", "rknee", "rankle", "rtoe")]
    err = {}
    for weight in (3.0, 0.0):
        rec, _ = run_method(get_method("dragposer", stand_weight=weight), tracking, motion.skeleton, progress=False)
        off = np.linalg.norm(fk(rec.local_rot, rec.root_pos, rec.skeleton.offsets)[0] - truth, axis=-1)
        err[weight] = (100 * off.mean(), 100 * off[:, legs].mean())
    assert err[3.0][1] < 0.85 * err[0.0][1], err  # the legs
    assert err[3.0][0] < err[0.0][0], err  # and the whole body
