"""Every constraint kind's fast-path term against its autograd loss, alone and on the
solver's two paths (shipped VAE, bundled clip)."""

from __future__ import annotations

import copy
import math
from pathlib import Path

import numpy as np
import pytest
import torch

from engine import skeleton as sk
from engine.constraints import REGISTRY, PoseState
from engine.constraints import (
    BalanceConstraint, BoundsConstraint, DistanceConstraint, EndEffectorConstraint, FloorConstraint,
    GroundConstraint, LookAtConstraint, PinConstraint, SmoothConstraint,
)  # fmt: skip
from engine.constraints.terms import FrameInputs, NativeTerm, axial
from engine.kinematics import quaternion as Q
from engine.kinematics.fk import fk_matrices
from engine.methods.dragposer import DragPoserMethod
from engine.motion.retarget import load_motion
from engine.tracking import simulate

J = sk.JOINT_INDEX
CLIP = Path(__file__).resolve().parents[2] / "assets" / "clips" / "example.bvh"
STAND = np.array([0.0, 0.0, 0.95])


def _random_pose(seed: int) -> tuple[np.ndarray, np.ndarray]:
    rng = np.random.default_rng(seed)
    local = np.tile([1.0, 0.0, 0.0, 0.0], (22, 1)) + rng.normal(0, 0.3, (22, 4))
    local /= np.linalg.norm(local, axis=-1, keepdims=True)
    pos, mats = fk_matrices(Q.to_matrix(torch.as_tensor(local)), torch.as_tensor(STAND), torch.as_tensor(sk.REST_OFFSETS))
    return pos.numpy(), mats.numpy()


def _cases(pos: np.ndarray) -> list:
    """Constraints of every kind with a pose term, each away from satisfied at ``pos``."""
    p = lambda j: pos[J[j]]  # noqa: E731
    smooth = SmoothConstraint(weight=3.0)
    smooth.set_history(pos + 0.03, pos)
    return [
        LookAtConstraint(weight=2.0, target=p("upperneck") + [0.9, -0.4, 0.3]),
        LookAtConstraint(joint="lwrist", axis=np.array([1.0, 0.2, 0.0]), target=p("lwrist") + [0.0, -0.5, 0.1]),
        FloorConstraint(weight=4.0, clearance=0.2, floor_height=0.05, contact_height=0.4, slide_weight=2.0),
        FloorConstraint(joints=("ltoe", "ltoe"), clearance=0.3),
        BalanceConstraint(weight=3.0, tolerance=0.01),
        BalanceConstraint(mode="com_over_feet", tolerance=0.0),
        DistanceConstraint(weight=5.0, distance=0.9),
        DistanceConstraint(joint_a="lankle", joint_b="upperneck", distance=0.2),
        BoundsConstraint(joint="lwrist", box_min=p("lwrist") + [0.05, -0.5, -0.5], box_max=p("lwrist") + [0.5, -0.02, 0.5]),
        PinConstraint(joint="rwrist", position=p("rwrist") + [0.0, -0.1, 0.05]),
        PinConstraint(name="follow", joint="lelbow", follow_previous=True),
        PinConstraint(name="unset", joint="rknee"),
        EndEffectorConstraint(joint="rankle", position=p("rankle") + [0.1, 0.0, 0.1]),
        EndEffectorConstraint(joint="lwrist", position=p("lwrist"), use_rotation=True, rotation_weight=0.7,
                              rotation=Q.from_axis_angle(np.array([0.3, 1.0, 0.0]), 1.1)),  # fmt: skip
        GroundConstraint(weight=2.0, low=0.6, high=0.7),
        smooth,
    ]  # fmt: skip


def test_every_kind_declares_a_fast_term():
    """Frames with any shipped kind stay on the fast path (none says it has no term)."""
    pos, _ = _random_pose(0)
    for kind, cls in REGISTRY.items():
        assert not cls.no_fast_term, kind
    kinds = {type(c).kind for c in _cases(pos)}
    assert kinds | {"sensor", "temporal_prior"} == set(REGISTRY)
    for c in _cases(pos):
        assert c.fast_term(FrameInputs(pos)) is not None


@pytest.mark.parametrize("seed", [1, 2])
@pytest.mark.parametrize("index", range(16))
def test_term_loss_and_gradients_equal_autograd(index, seed):
    """Loss, position gradient and rotation gradient of each term against autograd of
    the constraint's ``loss`` (positions and rotation matrices as free variables; for a
    turn ``W -> exp([a]x) W`` the change is ``-axial(W G^T) . a`` with ``G = dL/dW``)."""
    pos, mats = _random_pose(seed)
    prev = pos + np.random.default_rng(seed + 10).normal(0, 0.02, pos.shape)
    c = _cases(pos)[index]
    term = c.fast_term(FrameInputs(prev))
    assert not isinstance(term, NativeTerm)
    P = torch.tensor(pos, requires_grad=True)
    W = torch.tensor(mats, requires_grad=True)
    state = PoseState(P, None, torch.zeros(22, 4, dtype=torch.float64), torch.zeros(4, dtype=torch.float64),
                      torch.as_tensor(prev), 0, None, W)  # fmt: skip
    loss = c.loss(state)
    g_p, g_w = torch.autograd.grad(c.weight * loss, (P, W), allow_unused=True)
    g_p = np.zeros_like(pos) if g_p is None else g_p.numpy()
    g_w = np.zeros_like(mats) if g_w is None else g_w.numpy()
    want_rot = -np.stack([axial(mats[j] @ g_w[j].T) for j in range(22)])
    got_pos, got_rot = np.zeros_like(pos), np.zeros_like(pos)
    value = term.evaluate(pos, mats, got_pos, got_rot)
    assert float(loss.detach()) > 1e-6, "the case must be active"
    assert value == pytest.approx(float(loss.detach()), rel=1e-10, abs=1e-12)
    assert term.turns or not got_rot.any()
    np.testing.assert_allclose(got_pos, g_p, rtol=1e-9, atol=1e-11)
    np.testing.assert_allclose(got_rot, want_rot, rtol=1e-9, atol=1e-11)
    assert term.satisfied(pos, mats) == c.satisfied(state)
    assert term.weight == c.weight


@pytest.fixture(scope="module")
def models():
    from engine.models import load_default_models

    return load_default_models()


def _solve_both(models, kinds, preset="6", frames=6):
    """Both paths frame by frame from the same state; asserts the fast one never fell
    back to the reference path."""
    motion = load_motion(CLIP).slice(0, frames)
    tracking = simulate(motion, preset)
    head = tracking.positions[0, tracking.joints.index("upperneck")]
    fast = DragPoserMethod(models.vae, models.predictor, fast=True, iterations=10)
    fast.reset(motion.skeleton, motion.fps)
    fast.set_constraints(_scene(kinds, head))
    out = []
    for i in range(len(motion)):
        ref = copy.deepcopy(fast)  # the same state: float32 round-off does not build up over frames
        ref.optimizer._fast = None
        sols = [_recording(fast.optimizer), _recording(ref.optimizer)]
        fast.step(tracking.frame(i)), ref.step(tracking.frame(i))
        fast.optimizer.__dict__.pop("solve")
        (a,), (b,) = sols
        assert a.timings.fast and not a.slow_kinds, "the fast method used the reference path"
        assert not b.timings.fast
        out.append((a, b))
    return out


def _recording(optimizer) -> list:
    """The solutions ``optimizer.solve`` returns from now on."""
    seen, solve = [], optimizer.solve
    optimizer.solve = lambda *a: seen.append(solve(*a)) or seen[-1]
    return seen


def _scene(kinds, head):
    made = {
        "look_at": lambda: LookAtConstraint(name="look", target=head + [0.6, -0.8, 0.0]),
        "floor": lambda: FloorConstraint(name="floor", clearance=0.02),
        "pin": lambda: PinConstraint(name="pin", joint="lelbow"),
        "distance": lambda: DistanceConstraint(name="hands", distance=0.25),
        "balance": lambda: BalanceConstraint(name="balance", tolerance=0.02),
        "bounds": lambda: BoundsConstraint(name="box", joint="rwrist", box_min=np.array([-5.0, -5.0, 1.2]),
                                           box_max=np.array([5.0, 5.0, 3.0])),  # fmt: skip
        "end_effector": lambda: EndEffectorConstraint(name="reach", joint="lwrist", position=head + [0.3, -0.4, -0.2],
                                                      use_rotation=True),  # fmt: skip
    }
    return [made[k]() for k in kinds]


def _angle(ra: torch.Tensor, rb: torch.Tensor) -> np.ndarray:
    """Angles ``(22,)`` between two sets of rotation matrices ``(22, 3, 3)``, radians."""
    rel = torch.matmul(ra.double().transpose(-1, -2), rb.double()).numpy()
    sin = np.linalg.norm(np.stack([axial(r) for r in rel]), axis=-1) / 2.0  # arccos(trace) loses small angles
    return np.arcsin(sin.clip(0.0, 1.0))


@pytest.mark.parametrize("kinds", [("look_at",), ("floor",), ("pin",), ("distance",), ("balance",), ("bounds",),
                                   ("end_effector",), ("look_at", "floor", "pin", "distance")], ids="+".join)  # fmt: skip
def test_fast_path_frames_equal_the_reference(models, kinds):
    """Each kind with the six trackers, and the mix, solved on both paths from the same
    state, frame by frame: the same poses (1e-5 m, 1e-4 rad), latents and losses.

    Frame 0 is solved offline (up to 100 Adam steps), where float32 round-off grows to
    ~3e-4 m between the paths with the trackers alone; the realtime frames after it
    take 10 steps, as a live or ``reconstruct`` run does."""
    names = ("look", "floor", "pin", "hands", "balance", "box", "reach")
    active = set()
    for i, (a, b) in enumerate(_solve_both(models, kinds, frames=6 if len(kinds) > 1 else 4)):
        active |= {k for k in names if a.losses[0].get(k, 0.0) > 0.0}
        if i == 0:
            continue
        np.testing.assert_allclose(a.state.positions, b.state.positions, atol=1e-5, err_msg=f"frame {i}")
        assert _angle(a.state.rotation_matrices, b.state.rotation_matrices).max() < 1e-4, f"frame {i}"
        np.testing.assert_allclose(a.latent, b.latent, atol=1e-4, err_msg=f"frame {i}")
        for k in names:
            if k in a.losses[-1]:
                # abs: float32 resolution of a look-at loss 1 - cos near 0
                assert a.losses[-1][k] == pytest.approx(b.losses[-1][k], rel=1e-3, abs=2e-7), (i, k)
    assert len(active) == len(kinds), f"inactive terms: {set(kinds)} vs {active}"


def test_both_paths_weigh_a_constraint_by_its_activity_on_the_frame(models):
    """A constraint limited to a frame range acts with ``weight * activity(frame)``: in its
    blend the solve equals that of an every-frame copy with the scaled weight, on both
    paths; outside its range it is left out."""
    from engine.solver import FrameContext, OptimizerSettings, PoseOptimizer, RootFrame

    offsets = sk.Skeleton.canonical().offsets
    settings = OptimizerSettings(iterations=3, optimizer="sgd", step_size=0.5)
    fast, ref = PoseOptimizer(models.vae, offsets, settings), PoseOptimizer(models.vae, offsets, settings, fast=False)
    root = RootFrame(torch.tensor([1.0, 0, 0, 0]), torch.tensor([0.0, 0.0, 0.95]))
    ranged = LookAtConstraint(name="look", weight=2.0, target=np.array([1.0, -1.0, 1.2]), frames=(5, 9), blend_in=3)
    a = ranged.activity(3)
    assert 0.0 < a < 1.0
    plain = LookAtConstraint(name="look", weight=2.0 * a, target=ranged.target)
    z = torch.zeros(24)
    for opt in (fast, ref):
        blended = opt.solve(z, [ranged], FrameContext(root, frame=3))
        scaled = opt.solve(z, [plain], FrameContext(root, frame=3))
        assert blended.timings.fast == (opt is fast)
        np.testing.assert_array_equal(blended.latent.numpy(), scaled.latent.numpy())
        assert blended.losses[0]["total"] == pytest.approx(2.0 * a * blended.losses[0]["look"])
        outside = opt.solve(z, [ranged], FrameContext(root, frame=0))
        assert "look" not in outside.losses[0] and np.array_equal(outside.latent.numpy(), z.numpy())
    np.testing.assert_allclose(fast.solve(z, [ranged], FrameContext(root, frame=3)).latent.numpy(),
                               ref.solve(z, [ranged], FrameContext(root, frame=3)).latent.numpy(), atol=1e-5)  # fmt: skip
