"""Solver pieces: the ``smooth`` term on both paths, sensor-set profiles, the
heading limit and the adoption of tracker rotations."""

from __future__ import annotations

import copy
import math
from pathlib import Path

import numpy as np
import pytest
import torch

from engine import skeleton as sk
from engine.constraints import GroundConstraint, SensorConstraint, SmoothConstraint
from engine.kinematics import quat_np as QN
from engine.kinematics.fk import fk
from engine.methods.dragposer import DragPoserMethod
from engine.models import load_default_models
from engine.motion.retarget import load_motion
from engine.solver import FrameContext, OptimizerSettings, PoseOptimizer, RootAnchor, RootFrame
from engine.solver.limb_ik import finish
from engine.solver.pose import HEADING_LIMIT_DEG, body_facing, clamp_heading
from engine.solver.profiles import PROFILES, effective, profile_for
from engine.tracking import simulate

CLIP = Path(__file__).resolve().parents[2] / "assets" / "clips" / "example.bvh"


@pytest.fixture(scope="module")
def models():
    return load_default_models()


@pytest.mark.parametrize("preset, ground", [("6", 0.0), ("3-head-hands", 20.0), ("4", 20.0)])
def test_pose_terms_fast_path_equals_reference(models, preset, ground):
    """With ``smooth`` and ``ground`` terms active (ground band raised so it bites), every
    frame solved by the fast path (closed-form gradients) and by the autograd path from
    the same state agrees."""
    motion = load_motion(CLIP).slice(0, 10)
    tracking = simulate(motion, preset)
    # weights of the profiles' order (much stiffer ones make plain steps oscillate, and
    # the two paths' float32 round-off then grows into different trajectories)
    fast = DragPoserMethod(
        models.vae,
        models.predictor,
        fast=True,
        iterations=10,
        max_iterations=20,
        smooth_weight=5.0,
        ground_weight=ground,
    )
    fast.reset(motion.skeleton, motion.fps)
    fast.ground.low, fast.ground.high = 0.2, 0.25  # the clip's feet are below: the term is active
    seen = seen_ground = False
    for i in range(len(motion)):
        ref = copy.deepcopy(fast)
        ref.optimizer._fast = None
        a, b = fast.step(tracking.frame(i)), ref.step(tracking.frame(i))
        np.testing.assert_allclose(
            a.positions, b.positions, atol=1e-4
        )  # stiff weights amplify float32 round-off; exactness: the gradient test below
        assert a.losses[-1]["smooth"] == pytest.approx(b.losses[-1]["smooth"], rel=1e-3, abs=1e-9)
        seen |= a.losses[0]["smooth"] > 0
        if ground:
            # the band is one-sided and quadratic: at a loss of 1.5e-4 (weight 20, a foot 2.7 mm
            # past the band) d loss / d height is about 0.11, so feet 1e-5 m apart (float32
            # round-off grown over the frame's steps, BLAS builds differ in it) change the loss
            # by about 1e-6; 2e-7 is seen on frame 3 of 3-head-hands
            assert a.losses[-1]["ground"] == pytest.approx(b.losses[-1]["ground"], rel=1e-3, abs=1e-6)
            seen_ground |= a.losses[0]["ground"] > 0
    assert seen and (seen_ground or not ground)  # the terms were active
    assert fast.optimizer._fast is not None


def test_profiles_follow_the_connected_set_and_keep_explicit_settings():
    assert profile_for(["root", "upperneck", "lwrist", "rwrist", "lankle", "rankle"]).name == "full"
    assert (
        profile_for(["root", "upperneck", "lwrist", "rwrist", "lankle", "rankle"], hip_rotation=False).name == "full3"
    )
    assert profile_for(["root", "lwrist", "rwrist"]).name == "hip"
    assert profile_for(["upperneck", "lwrist", "rwrist"]).name == "head"
    s = OptimizerSettings(temporal_weight=0.123)
    eff = effective(s, ["upperneck", "lwrist", "rwrist"], {"temporal_weight"})
    assert eff.temporal_weight == 0.123 and eff.future_window == PROFILES["head"].values()["future_window"]
    assert effective(OptimizerSettings(tuning="off"), ["upperneck"], set()).future_window == 0


def test_method_records_explicit_settings():
    m = DragPoserMethod(_Zero(), temporal_weight=0.5)
    assert "temporal_weight" in m.explicit and "lr" not in m.explicit
    m.configure(lr=0.1)
    assert "lr" in m.explicit


class _Zero(torch.nn.Module):
    def decode(self, z):
        rot = torch.zeros(z.shape[0], 22, 4)
        rot[..., 0] = 1.0
        return rot, torch.zeros(z.shape[0], 3)


def _yaw(q):
    f = QN.rotate(q, np.array([0.0, -1.0, 0.0]))
    return math.degrees(math.atan2(f[0], -f[1]))


def test_clamp_heading_limits_the_reference_to_the_anchor():
    about_z = lambda deg: np.array([math.cos(math.radians(deg) / 2), 0, 0, math.sin(math.radians(deg) / 2)])  # noqa: E731
    head = about_z(10.0)
    assert np.allclose(clamp_heading(about_z(40.0), head), about_z(40.0))  # within the limit
    out = clamp_heading(about_z(175.0), head)
    assert _yaw(out) == pytest.approx(10.0 + HEADING_LIMIT_DEG, abs=1e-6)
    out = clamp_heading(about_z(-120.0), head)
    assert _yaw(out) == pytest.approx(10.0 - HEADING_LIMIT_DEG, abs=1e-6)
    # a head looking straight down has no heading: nothing is changed
    down = np.array([math.cos(math.pi / 4), math.sin(math.pi / 4), 0, 0])
    assert np.allclose(clamp_heading(about_z(175.0), down), about_z(175.0))


def test_adopt_rotations_sets_world_rotation_and_keeps_positions():
    rng = np.random.default_rng(0)
    local = rng.normal(size=(22, 4))
    local /= np.linalg.norm(local, axis=-1, keepdims=True)
    offsets = sk.Skeleton.canonical().offsets
    root = np.array([0.1, 0.2, 0.9])
    target = rng.normal(size=4)
    target /= np.linalg.norm(target)
    j = sk.JOINT_INDEX["lankle"]
    new, pos = finish(local, root, offsets, {}, {j: target})
    old_pos, _ = fk(local, root, offsets)
    _, world = fk(new, root, offsets)
    assert abs(abs(float(world[j] @ target)) - 1.0) < 1e-9
    np.testing.assert_allclose(pos[: j + 1], old_pos[: j + 1], atol=1e-12)  # the ankle and all before it
    assert np.linalg.norm(pos[j + 1] - old_pos[j + 1]) > 1e-3  # the toe follows the new foot rotation


@pytest.mark.parametrize("anchor", [False, True])
def test_pose_term_gradients_equal_autograd(models, anchor):
    """One plain gradient step from the same latent on both paths: the fast path's
    closed-form gradient of sensors + smooth + ground equals autograd's."""
    rng = np.random.default_rng(3)
    offsets = sk.Skeleton.canonical().offsets
    rest = sk.Skeleton.canonical().rest_positions() + np.array([0.0, 0.0, 0.95])
    sensors = [
        SensorConstraint(
            name=f"sensor:{j}",
            joint=j,
            position=rest[sk.JOINT_INDEX[j]] + rng.normal(0, 0.05, 3),
            rotation=_unit(rng.normal(size=4)),
        )
        for j in ("upperneck", "lwrist", "rwrist")
    ]
    smooth = SmoothConstraint(weight=30.0)
    smooth.set_history(rest + rng.normal(0, 0.03, rest.shape), rest)
    ground = GroundConstraint(weight=80.0, low=0.3, high=0.35)
    terms = [*sensors, smooth, ground]
    head = sk.JOINT_INDEX["upperneck"]
    ctx = FrameContext(
        RootFrame(torch.tensor([1.0, 0, 0, 0]), torch.tensor([0.0, 0.0, 0.95])),
        root_anchor=RootAnchor(head, torch.as_tensor(sensors[0].position, dtype=torch.float32)) if anchor else None,
    )
    settings = OptimizerSettings(iterations=1, optimizer="sgd", step_size=1.0)
    fast = PoseOptimizer(models.vae, offsets, settings)
    ref = PoseOptimizer(models.vae, offsets, settings, fast=False)
    z0 = torch.as_tensor(rng.normal(0, 0.5, 24), dtype=torch.float32)
    a, b = fast.solve(z0, terms, ctx), ref.solve(z0, terms, ctx)
    assert a.timings.fast and not b.timings.fast
    assert a.losses[0]["ground"] > 0 and a.losses[0]["smooth"] > 0
    np.testing.assert_allclose((z0 - a.latent).numpy(), (z0 - b.latent).numpy(), rtol=1e-3, atol=1e-5)


def _unit(q):
    return q / np.linalg.norm(q)


def test_reach_puts_the_end_joint_on_a_reachable_target_and_keeps_its_rotation():
    rng = np.random.default_rng(5)
    skel = sk.Skeleton.canonical()
    local = np.tile([1.0, 0, 0, 0], (22, 1)) + rng.normal(0, 0.15, (22, 4))
    local /= np.linalg.norm(local, axis=-1, keepdims=True)
    root = np.array([0.0, 0.0, 0.95])
    pos, world = fk(local, root, skel.offsets)
    wrist, ankle = sk.JOINT_INDEX["lwrist"], sk.JOINT_INDEX["rankle"]
    shoulder, hip = sk.JOINT_INDEX["lshoulder"], sk.JOINT_INDEX["rhip"]
    # pulled towards the limb root (so within reach) and sideways
    targets = {
        wrist: pos[wrist] + 0.2 * (pos[shoulder] - pos[wrist]) + [0.0, 0.03, 0.0],
        ankle: pos[ankle] + 0.15 * (pos[hip] - pos[ankle]) + [0.03, 0.0, 0.0],
    }
    new, new_pos = finish(local, root, skel.offsets, targets, {})
    _, new_world = fk(new, root, skel.offsets)
    for j, t in targets.items():
        assert np.linalg.norm(new_pos[j] - t) < 1e-6
        assert abs(abs(float(new_world[j] @ world[j])) - 1.0) < 1e-9  # same world rotation
    untouched = [k for k in range(22) if k not in (15, 16, 17, 5, 6, 7, 8)]
    np.testing.assert_allclose(new_pos[untouched], pos[untouched], atol=1e-12)
    # beyond reach: the limb points straight at the target
    far = {wrist: pos[sk.JOINT_INDEX["lshoulder"]] + [2.0, 0, 0]}
    _, far_pos = finish(local, root, skel.offsets, far, {})
    d = far_pos[wrist] - far_pos[sk.JOINT_INDEX["lshoulder"]]
    assert d[0] / np.linalg.norm(d) > 0.999


def _about_z(deg: float) -> np.ndarray:
    return np.array([math.cos(math.radians(deg) / 2), 0.0, 0.0, math.sin(math.radians(deg) / 2)])


@pytest.mark.parametrize("yaw", [-100.0, 0.0, 35.0, 170.0])
def test_body_facing_reads_the_heading_off_feet_and_hands(yaw):
    rest = sk.Skeleton.canonical().rest_positions()
    turned = QN.rotate(np.broadcast_to(_about_z(yaw), (22, 4)), rest)
    points = {n: turned[sk.JOINT_INDEX[n]] for n in ("lankle", "rankle", "lwrist", "rwrist", "root")}
    assert _yaw(body_facing(points)) == pytest.approx(yaw, abs=2.0)  # the rest pose's feet are ~1 deg off X
    assert _yaw(body_facing({k: points[k] for k in ("lwrist", "rwrist")})) == pytest.approx(yaw, abs=2.0)
    assert body_facing({k: points[k] for k in ("lankle", "root", "rwrist")}) is None  # no left-right pair


@pytest.mark.parametrize("turn", [90.0, 180.0])
def test_hip_without_rotation_turns_with_the_wearer(models, turn):
    """6x3dof: the same motion turned about +Z is reconstructed turned the same way.
    Before the body-heading rule the first frame faced -Y whatever the trackers said, so
    the turned clip came out 60-90 deg off on validation clips."""
    q = _about_z(turn)

    def solve(m):
        tracking = simulate(m, "6x3dof")
        method = DragPoserMethod(models.vae, models.predictor, iterations=10)
        method.reset(m.skeleton, m.fps)
        return [method.step(tracking.frame(i)) for i in range(len(m))]

    plain = load_motion(CLIP, max_frames=4)
    turned = load_motion(CLIP, max_frames=4)
    turned.local_rot[:, 0] = QN.mul(np.broadcast_to(q, (len(turned), 4)), turned.local_rot[:, 0])
    turned.root_pos = QN.rotate(np.broadcast_to(q, (len(turned), 4)), turned.root_pos)
    for i, (a, b) in enumerate(zip(solve(plain), solve(turned))):
        err = math.remainder(math.radians(_yaw(b.local_rot[0]) - _yaw(a.local_rot[0]) - turn), 2 * math.pi)
        assert abs(math.degrees(err)) < 2.0, f"frame {i}"
        moved = QN.rotate(np.broadcast_to(q, (22, 4)), a.positions)
        assert np.abs(b.positions - moved).max() < 0.01, f"frame {i}"


def test_root_is_held_when_nothing_places_the_body(models):
    """Only the hands connected (hips, head and feet lost, as ``--faulty`` can do): the
    root must not run away on the integrated decoded displacement (it moved 3 m within
    70 frames on a validation clip)."""
    m = load_motion(CLIP, max_frames=70)
    tracking = simulate(m, "6")
    lost = [tracking.joints.index(j) for j in ("root", "upperneck", "lankle", "rankle")]
    tracking.connected[10:, lost] = False
    method = DragPoserMethod(models.vae, models.predictor, iterations=10)
    method.reset(m.skeleton, m.fps)
    res = [method.step(tracking.frame(i)) for i in range(len(m))]
    drift = np.linalg.norm(res[-1].root_pos[:2] - m.root_pos[-1, :2])
    assert drift < 0.15, f"root {drift:.2f} m from the truth after 60 frames without hips or head"
    assert abs(res[-1].root_pos[2] - res[9].root_pos[2]) < 1e-4  # height held


def test_the_fast_path_takes_a_joint_anchor_and_names_any_other(models):
    """``FrameContext.root_anchor`` is any :class:`BodyAnchor`: the autograd decode applies
    the authoring's ``Ground``; the fast objective, which places a body by one joint
    only, refuses it by name instead of failing on a missing attribute."""
    from engine.authoring.character import Ground
    from engine.solver.pose import BodyAnchor, JointAnchor

    ground = Ground(torch.tensor([0.4, -0.2]), torch.zeros(4))
    head = RootAnchor(sk.JOINT_INDEX["upperneck"], torch.tensor([0.0, 0.0, 1.6]))
    assert isinstance(ground, BodyAnchor) and not isinstance(ground, JointAnchor)
    assert isinstance(head, JointAnchor)
    root = RootFrame(torch.tensor([1.0, 0.0, 0.0, 0.0]), torch.zeros(3))
    z0 = torch.zeros(models.vae.config.latent)
    wrist = SensorConstraint(name="sensor:lwrist", joint="lwrist", dof=3, position=np.array([0.3, 0.0, 1.0]))
    fast = PoseOptimizer(models.vae, sk.REST_OFFSETS, OptimizerSettings(iterations=2))
    held = fast.solve(z0, [wrist], FrameContext(root, root_anchor=head))
    assert torch.allclose(held.state.positions[sk.JOINT_INDEX["upperneck"]], head.position, atol=1e-5)
    with pytest.raises(TypeError, match="root_anchor.*Ground"):
        fast.solve(z0, [wrist], FrameContext(root, root_anchor=ground))
    reference = PoseOptimizer(models.vae, sk.REST_OFFSETS, OptimizerSettings(iterations=2), fast=False)
    placed = reference.solve(z0, [wrist], FrameContext(root, root_anchor=ground))
    assert torch.allclose(placed.state.positions[0, :2], ground.xy, atol=1e-6)
