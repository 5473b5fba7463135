"""The solver's two objectives on the same frames: the numpy one (fused decoder, closed
form chain, the terms' Jacobians) against the autograd reference, with every user
constraint kind (shipped VAE, bundled clip). Each kind's term alone is checked in
``test_terms.py``."""

from __future__ import annotations

import copy
from pathlib import Path

import numpy as np
import pytest
import torch

from engine import skeleton as sk
from engine.constraints import (
    REGISTRY,
    BalanceConstraint,
    BoundsConstraint,
    DistanceConstraint,
    EndEffectorConstraint,
    FloorConstraint,
    LookAtConstraint,
    PinConstraint,
)
from engine.methods.dragposer import DragPoserMethod
from engine.motion.retarget import load_motion
from engine.tracking import simulate

J = sk.JOINT_INDEX
CLIP = Path(__file__).resolve().parents[2] / "assets" / "clips" / "example.bvh"
STAND = np.array([0.0, 0.0, 0.95])


@pytest.fixture(scope="module")
def models():
    from engine.models import load_default_models

    return load_default_models()


def _solve_both(models, constraints, preset="6", frames=6):
    """Both paths frame by frame from the same state, with ``constraints`` (or a function
    of the first frame's pose giving them); asserts the fast one never fell back to the
    reference path."""
    motion = load_motion(CLIP).slice(0, frames)
    tracking = simulate(motion, preset)
    if callable(constraints):
        constraints = constraints(motion.positions()[0])
    fast = DragPoserMethod(models.vae, models.predictor, fast=True, iterations=10)
    fast.reset(motion.skeleton, motion.fps)
    fast.set_constraints(constraints)
    out = []
    for i in range(len(motion)):
        ref = copy.deepcopy(fast)  # the same state: float32 round-off does not build up over frames
        ref.optimizer._fast = None
        sols = [_recording(fast.optimizer), _recording(ref.optimizer)]
        fast.step(tracking.frame(i)), ref.step(tracking.frame(i))
        fast.optimizer.__dict__.pop("solve")
        (a,), (b,) = sols
        assert a.timings.fast, "the fast method used the reference path"
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
        "bounds": lambda: BoundsConstraint(
            name="box", joint="rwrist", box_min=np.array([-5.0, -5.0, 1.2]), box_max=np.array([5.0, 5.0, 3.0])
        ),
        "end_effector": lambda: EndEffectorConstraint(
            name="reach", joint="lwrist", position=head + [0.3, -0.4, -0.2], use_rotation=True
        ),
    }
    return [made[k]() for k in kinds]


def axial(m: np.ndarray) -> np.ndarray:
    return np.array([m[2, 1] - m[1, 2], m[0, 2] - m[2, 0], m[1, 0] - m[0, 1]])


def _angle(ra: torch.Tensor, rb: torch.Tensor) -> np.ndarray:
    """Angles ``(22,)`` between two sets of rotation matrices ``(22, 3, 3)``, radians."""
    rel = torch.matmul(ra.double().transpose(-1, -2), rb.double()).numpy()
    sin = np.linalg.norm(np.stack([axial(r) for r in rel]), axis=-1) / 2.0  # arccos(trace) loses small angles
    return np.arcsin(sin.clip(0.0, 1.0))


USER_KINDS = sorted(k for k, c in REGISTRY.items() if c.user_facing)


def _compare(pairs, names, frames_checked_from=1):
    active = set()
    for i, (a, b) in enumerate(pairs):
        active |= {k for k in names if a.losses[0].get(k, 0.0) > 0.0}
        if i < frames_checked_from:
            continue
        np.testing.assert_allclose(a.state.positions, b.state.positions, atol=1e-5, err_msg=f"frame {i}")
        assert _angle(a.state.rotation_matrices, b.state.rotation_matrices).max() < 1e-4, f"frame {i}"
        np.testing.assert_allclose(a.latent, b.latent, atol=1e-4, err_msg=f"frame {i}")
        for k in names:
            if k in a.losses[-1]:
                # abs: float32 resolution of a look-at loss 1 - cos near 0
                assert a.losses[-1][k] == pytest.approx(b.losses[-1][k], rel=1e-3, abs=2e-7), (i, k)
    return active


@pytest.mark.parametrize("kind", USER_KINDS)
def test_fast_path_frames_equal_the_reference(models, kind):
    """Each user-facing kind of the registry (its first example, placed at the clip's first
    pose) with the six trackers, solved on both objectives from the same state, frame by
    frame: the same poses (1e-5 m, 1e-4 rad), latents and losses.

    Frame 0 is solved offline (up to 100 Adam steps), where float32 round-off grows to
    ~3e-4 m between the paths with the trackers alone; the realtime frames after it
    take 10 steps, as a live or ``reconstruct`` run does."""
    make = lambda pose: [REGISTRY[kind].examples(pose)[0]]  # noqa: E731
    active = _compare(_solve_both(models, make, frames=4), (kind,))
    assert active == {kind}, f"{kind}: its example does not act on the clip's first frame"


def test_fast_path_frames_equal_the_reference_with_several_kinds(models):
    """Look-at, floor, pin and distance together, as the shipped scene has them."""
    tracking = simulate(load_motion(CLIP).slice(0, 1), "6")
    head = tracking.positions[0, tracking.joints.index("upperneck")]
    names = ("look", "floor", "pin", "hands")
    active = _compare(_solve_both(models, _scene(("look_at", "floor", "pin", "distance"), head)), names)
    assert active == set(names)


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
    np.testing.assert_allclose(
        fast.solve(z, [ranged], FrameContext(root, frame=3)).latent.numpy(),
        ref.solve(z, [ranged], FrameContext(root, frame=3)).latent.numpy(),
        atol=1e-5,
    )
