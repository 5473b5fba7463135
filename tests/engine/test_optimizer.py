"""Pose optimizer: FK, root handling, modes, per-term reporting, robustness, schedule."""

from __future__ import annotations

import math
import time

import numpy as np
import pytest
import torch

from engine import skeleton as sk
from engine.constraints import EndEffectorConstraint, SensorConstraint, TemporalPriorConstraint
from engine.errors import UserError
from engine.kinematics import quaternion as Q
from engine.solver import (
    FrameContext,
    OptimizerSettings,
    PoseOptimizer,
    RootAnchor,
    RootFrame,
    RootOverride,
    TemporalSchedule,
)
from tests.engine.test_optimizer_standins import CountingPredictor, MLPDecoder, NaNBeyond

J = sk.JOINT_INDEX
OFFSETS = sk.REST_OFFSETS


def ctx(**kw) -> FrameContext:
    root = RootFrame(torch.tensor([1.0, 0.0, 0.0, 0.0]), torch.tensor([0.0, 0.0, 1.0]))
    return FrameContext(root, **kw)


def targets_from(
    opt: PoseOptimizer,
    z: torch.Tensor,
    c: FrameContext,
    joints=("root", "upperneck", "lwrist", "rwrist", "lankle", "rankle"),
) -> list[SensorConstraint]:
    """Sensors placed on the decoded pose of ``z``: a reachable target set."""
    with torch.no_grad():
        s = opt.decode(z, c)
    return [
        SensorConstraint(
            name=f"sensor:{j}",
            joint=j,
            position=s.positions[J[j]].double().numpy(),
            rotation=s.world_rotations()[J[j]].double().numpy(),
        )
        for j in joints
    ]


def test_root_follows_a_hip_sensor_or_integrates_the_decoded_displacement():
    opt = PoseOptimizer(MLPDecoder(), OFFSETS)
    z = torch.randn(24) * 0.3
    yaw = Q.from_axis_angle(np.array([0.0, 0.0, 1.0]), 0.7)
    prev = RootFrame(torch.tensor(yaw, dtype=torch.float32), torch.tensor([1.0, 2.0, 0.9]))
    with torch.no_grad():
        rot, disp = opt.decoder.decode(z[None])
        free = opt.decode(z, FrameContext(prev))
        h = torch.tensor(yaw, dtype=torch.float32)
        assert torch.allclose(free.positions[0], prev.position + Q.rotate(h, disp[0]), atol=1e-6)
        assert torch.allclose(free.local_rot[0], Q.mul(h, rot[0, 0]), atol=1e-6)
        hip = RootOverride(torch.tensor([5.0, 5.0, 1.0]), torch.tensor([0.0, 0.0, 0.0, 1.0]))
        held = opt.decode(z, FrameContext(prev, hip))
        assert torch.allclose(held.positions[0], hip.position) and torch.allclose(held.local_rot[0], hip.rotation)
        assert torch.allclose(held.local_rot[1:], free.local_rot[1:])


def test_without_hip_sensor_the_head_anchor_places_the_body():
    opt = PoseOptimizer(MLPDecoder(), OFFSETS)
    z = torch.randn(24) * 0.3
    head = torch.tensor([3.0, -1.0, 1.6])
    anchor = RootAnchor(J["upperneck"], head)
    with torch.no_grad():
        free = opt.decode(z, ctx())
        held = opt.decode(z, ctx(root_anchor=anchor))
        assert torch.allclose(held.positions[J["upperneck"]], head, atol=1e-6)
        shift = held.positions - free.positions  # a rigid translation of the decoded pose
        assert torch.allclose(shift, shift[:1].expand_as(shift), atol=1e-5)
        assert torch.allclose(held.local_rot, free.local_rot)
        hip = RootOverride(torch.tensor([5.0, 5.0, 1.0]))
        both = opt.decode(z, ctx(root_override=hip, root_anchor=anchor))
        assert torch.allclose(both.positions[0], hip.position), "a hip sensor takes precedence"
    # the anchored body stays put however far the decoded displacement would carry it
    zs = torch.zeros(24, requires_grad=True)
    s1 = opt.decode(zs, ctx(root_anchor=anchor))
    s1.positions[J["upperneck"]].sum().backward()
    assert zs.grad.abs().max() < 1e-5, "the head's position no longer depends on the latent"


def test_sgd_takes_the_papers_plain_gradient_step_and_adam_carry_keeps_its_moments():
    z0 = torch.randn(24) * 0.2
    opt = PoseOptimizer(MLPDecoder(), OFFSETS, OptimizerSettings(optimizer="sgd", step_size=0.3, iterations=1))
    c = ctx()
    terms = targets_from(opt, torch.zeros(24), c, ("lwrist",))
    z = z0.clone().requires_grad_(True)
    terms[0].loss(opt.decode(z, c)).backward()
    sol = opt.solve(z0, terms, c)
    assert torch.allclose(sol.latent, z0 - 0.3 * z.grad, atol=1e-6)
    carry = PoseOptimizer(MLPDecoder(), OFFSETS, OptimizerSettings(optimizer="adam-carry", iterations=3))
    fresh = PoseOptimizer(MLPDecoder(), OFFSETS, OptimizerSettings(optimizer="adam", iterations=3))
    first = [o.solve(z0, terms, c).latent for o in (carry, fresh)]
    assert torch.allclose(first[0], first[1]), "the first frame has nothing to carry"
    second = [o.solve(first[0], terms, c).latent for o in (carry, fresh)]
    assert not torch.allclose(second[0], second[1]), "carried moments change the next frame's steps"


def test_carried_moments_are_dropped_after_frames_under_another_rule():
    """auto switches to plain steps while a tracker is lost; Adam starts afresh after."""
    z0 = torch.randn(24) * 0.2
    opt = PoseOptimizer(MLPDecoder(), OFFSETS, OptimizerSettings(iterations=3))
    c = ctx()
    six = targets_from(opt, torch.zeros(24), c)
    opt.solve(z0, six, c)
    assert opt._carry, "six sensors: Adam's moments are kept for the next frame"
    opt.solve(z0, six[:5], c)
    assert opt._carry == {}, "a frame of plain steps leaves nothing to carry"


def test_auto_uses_carried_adam_with_six_sensors_and_plain_steps_with_fewer():
    opt = PoseOptimizer(MLPDecoder(), OFFSETS)
    six = targets_from(opt, torch.zeros(24), ctx())
    assert opt.settings.optimizer == "auto"
    assert opt.update_rule(six) == "adam-carry" and opt.update_rule(six[:4]) == "sgd"
    assert opt.update_rule(six[:4] + [TemporalPriorConstraint()]) == "sgd", "only sensors count"
    opt.settings.optimizer = "adam"
    assert opt.update_rule(six[:1]) == "adam"


def test_a_deadline_takes_fresh_adam_moments_and_keeps_none():
    """Live (a deadline): carried moments make steps too small for the 3-4 iterations a
    frame gets, so ``auto`` starts Adam afresh each frame and carries nothing."""
    opt = PoseOptimizer(MLPDecoder(), OFFSETS)
    six = targets_from(opt, torch.zeros(24), ctx())
    assert opt.update_rule(six, deadline=True) == "adam" and opt.update_rule(six[:4], deadline=True) == "sgd"
    live = ctx(deadline=time.perf_counter() + 60.0)
    opt.solve(torch.zeros(24), six, live)
    assert opt._carry == {}
    opt.settings.optimizer = "adam-carry"  # an explicit choice is kept
    assert opt.update_rule(six, deadline=True) == "adam-carry"


def test_without_hip_sensor_other_constraints_move_the_root():
    opt = PoseOptimizer(MLPDecoder(), OFFSETS)
    z = torch.zeros(24, requires_grad=True)
    s = opt.decode(z, ctx())
    target = s.positions[J["upperneck"]].detach() + torch.tensor([0.0, 0.0, 0.05])
    ((s.positions[J["upperneck"]] - target) ** 2).sum().backward()
    assert z.grad is not None and z.grad.abs().sum() > 0


def test_realtime_takes_the_fixed_step_count_and_reports_every_term():
    torch.manual_seed(1)
    opt = PoseOptimizer(MLPDecoder(), OFFSETS, OptimizerSettings(iterations=7, lr=0.05))
    c = ctx()
    sensors = targets_from(opt, torch.randn(24) * 0.4, c)
    sol = opt.solve(torch.zeros(24), sensors, c)
    assert sol.iterations == 7 and len(sol.losses) == 8 and not sol.warnings
    assert set(sol.losses[0]) == {s.name for s in sensors} | {"total"}
    assert sol.losses[-1]["total"] < sol.losses[0]["total"]
    assert sol.losses[0]["total"] == pytest.approx(sum(v for k, v in sol.losses[0].items() if k != "total"), rel=1e-5)


def test_offline_stops_when_the_tolerances_are_met_and_respects_the_cap():
    torch.manual_seed(2)
    settings = OptimizerSettings(mode="offline", max_iterations=300, lr=0.05, patience=300)
    opt = PoseOptimizer(MLPDecoder(), OFFSETS, settings)
    c = ctx()
    goal = torch.randn(24) * 0.4
    sensors = targets_from(opt, goal, c)
    start = goal + 0.1 * torch.randn(24)  # nearby, as consecutive frames are
    sol = opt.solve(start, sensors, c)
    assert 0 < sol.iterations < 300
    assert all(s.satisfied(sol.state) for s in sensors)
    settings.max_iterations = 3  # applies to the next solve
    assert opt.solve(start, sensors, c).iterations == 3


def test_offline_stops_when_the_loss_stops_improving():
    opt = PoseOptimizer(MLPDecoder(), OFFSETS, OptimizerSettings(mode="offline", max_iterations=500, patience=5))
    impossible = [EndEffectorConstraint(joint="lwrist", position=np.array([50.0, 0.0, 0.0]))]
    sol = opt.solve(torch.zeros(24), impossible, ctx())
    assert sol.iterations < 500


def test_nan_target_is_left_out_with_a_warning_and_the_rest_is_solved():
    torch.manual_seed(3)
    opt = PoseOptimizer(MLPDecoder(), OFFSETS, OptimizerSettings(lr=0.02))
    c = ctx()
    good = targets_from(opt, torch.randn(24) * 0.1, c, joints=("lwrist",))
    bad = EndEffectorConstraint(name="broken", position=np.array([np.nan, 0.0, 1.0]))
    sol = opt.solve(torch.zeros(24), [*good, bad], c)
    assert any("broken" in w for w in sol.warnings)
    assert torch.isfinite(sol.latent).all() and torch.isfinite(sol.state.positions).all()
    assert "broken" not in sol.losses[0] and sol.losses[-1]["total"] < sol.losses[0]["total"]


def test_a_loss_that_turns_non_finite_falls_back_to_the_start():
    dec = NaNBeyond(limit=0.2)
    opt = PoseOptimizer(dec, OFFSETS, OptimizerSettings(iterations=20, lr=0.1))
    far = [EndEffectorConstraint(joint="lwrist", position=np.array([3.0, 0.0, 1.0]))]
    start = torch.full((24,), 0.1)
    sol = opt.solve(start, far, ctx())
    assert sol.fell_back and sol.warnings and torch.equal(sol.latent, start)
    assert torch.isfinite(sol.state.positions).all()


def test_a_diverging_loss_falls_back():
    opt = PoseOptimizer(MLPDecoder(), OFFSETS, OptimizerSettings(iterations=5, lr=5.0, divergence_factor=1.0))
    c = ctx()
    sensors = targets_from(opt, torch.zeros(24), c)  # satisfied at the start: any move is worse
    sol = opt.solve(torch.zeros(24), sensors, c)
    assert sol.fell_back and "diverged" in sol.warnings[-1]


def test_temporal_prior_pulls_towards_the_prediction():
    opt = PoseOptimizer(MLPDecoder(), OFFSETS, OptimizerSettings(iterations=30, lr=0.05))
    pred = torch.full((24,), 0.5)
    sol = opt.solve(torch.zeros(24), [TemporalPriorConstraint()], ctx(prediction=pred))
    assert (sol.latent - pred).norm() < 0.5 * pred.norm()


@pytest.mark.parametrize(
    "field, value",
    [
        ("mode", "turbo"),
        ("iterations", 0),
        ("lr", -1.0),
        ("lr", math.nan),
        ("max_iterations", 2.5),
        ("optimizer", "lbfgs"),
        ("root_anchor", "tail"),
    ],
)
def test_bad_settings_name_the_field(field, value):
    with pytest.raises(UserError, match=field):
        OptimizerSettings(**{field: value})


def test_schedule_runs_the_predictor_every_n_frames_per_future_window():
    for future, expected in ((1, [1, 4, 8, 12, 16]), (4, [1, 16])):
        sched, pred, ran = TemporalSchedule(every=4, past=16), CountingPredictor(), []
        for i in range(20):
            before = len(pred.calls)
            z, warn = sched.prediction(i, pred, future)
            assert not warn and (z is None) == (i == 0)
            if len(pred.calls) > before:
                ran.append(i)
            sched.record(i, torch.full((24,), float(i)), torch.zeros(9))
        assert ran == expected, future
        assert pred.calls[-1] == ((1, 16, 24), (1, 16, 9), future)


def test_schedule_survives_a_failing_predictor():
    class Broken:
        def predict(self, *a, **k):
            raise RuntimeError("boom")

    sched = TemporalSchedule()
    sched.record(0, torch.zeros(24), torch.zeros(9))
    z, warn = sched.prediction(1, Broken(), 1)
    assert z is None and "boom" in warn
