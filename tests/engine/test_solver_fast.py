"""The solver's fast path (fused decoder, hand-derived gradients) against the reference
path (autograd through the torch model), on the shipped VAE and the bundled clip."""

from __future__ import annotations

import copy
from pathlib import Path

import numpy as np
import pytest
import torch

from engine.kinematics import quaternion as Q
from engine.methods.dragposer import DragPoserMethod
from engine.models import load_default_models
from engine.models.fused import DenseDecoder, _matvec, plan_runs
from engine.motion.retarget import load_motion
from engine.solver import LatentUpdate
from engine.tracking import simulate

CLIP = Path(__file__).resolve().parents[2] / "assets" / "clips" / "example.bvh"


@pytest.fixture(scope="module")
def models():
    return load_default_models()


def test_dense_decoder_equals_the_model_and_its_gradient_equals_autograd(models):
    vae = models.vae
    dense = DenseDecoder(vae)
    gen = torch.Generator().manual_seed(1)
    for _ in range(3):
        z = torch.randn(24, generator=gen) * 0.7
        out = dense.forward(z.numpy())
        rot, disp = vae.decode(z[None])
        q = Q.canonicalize(Q.normalize(torch.as_tensor(out[:88]).reshape(22, 4)))
        assert torch.allclose(q, rot[0], atol=2e-6)
        assert torch.allclose(torch.as_tensor(out[88:]), disp[0], atol=2e-6)
        # gradient of a random linear function of the raw output, against autograd
        g = torch.randn(91, generator=gen)
        zz = z.clone().requires_grad_(True)
        x = vae.act(vae.from_latent(zz[None])).reshape(1, 6, 96)
        x = vae.act(vae.dec[0](torch.matmul(vae.unpool2, x)))
        x = vae.act(vae.dec[1](torch.matmul(vae.unpool1, x)))
        x = vae.act(vae.dec[2](torch.matmul(vae.unpool0, x)))
        x = vae.act(vae.dec[3](x))
        raw = torch.cat(((vae.to_rot(x) + torch.tensor([1.0, 0, 0, 0])).flatten(1),
                         vae.to_disp(x[:, 0]) * vae.disp_std + vae.disp_mean), dim=1)  # fmt: skip
        (raw[0] @ g).backward()
        assert torch.allclose(torch.as_tensor(out), raw[0].detach(), atol=2e-6)
        np.testing.assert_allclose(dense.backward(g.numpy()), zz.grad.numpy(), rtol=1e-4, atol=1e-5)


def test_run_planner_keeps_only_the_blocks_worth_a_call():
    w = np.zeros((6, 6), dtype=np.float32)
    w[0:2, 0:2], w[2:4, 2:4], w[4:6, 4:6] = 1.0, 2.0, 3.0  # block diagonal, 3 nodes of 2
    nodes = [(0, 2), (2, 4), (4, 6)]
    runs = plan_runs(w, nodes, nodes, call_cost=0)
    assert [(r.r0, r.r1, r.c0, r.c1) for r in runs] == [(0, 2, 0, 2), (2, 4, 2, 4), (4, 6, 4, 6)]
    one = plan_runs(w, nodes, nodes, call_cost=1e9)
    assert [(r.r0, r.r1, r.c0, r.c1) for r in one] == [(0, 6, 0, 6)]
    x = np.arange(6, dtype=np.float32)
    for plan in (runs, one):
        np.testing.assert_array_equal(_matvec(plan, x, np.empty(6, np.float32)), w @ x)


def test_block_sparse_decoder_reads_less_and_equals_the_dense_products(models):
    dense = DenseDecoder(models.vae)
    total = sum(w.size for w in dense.weights)
    fwd, bwd = dense.stored_entries()
    assert fwd < 0.6 * total and bwd < 0.6 * total  # 1.77 M entries, 0.64 M of them not zero
    gen = np.random.default_rng(3)
    for w, fr, br in zip(dense.weights, dense.forward_runs, dense.backward_runs):
        x = gen.standard_normal(w.shape[1]).astype(np.float32)
        g = gen.standard_normal(w.shape[0]).astype(np.float32)
        np.testing.assert_allclose(_matvec(fr, x, np.empty(w.shape[0], np.float32)), w @ x, rtol=1e-5, atol=1e-5)
        np.testing.assert_allclose(_matvec(br, g, np.empty(w.shape[1], np.float32)), g @ w, rtol=1e-5, atol=1e-5)


def test_solvers_on_one_model_keep_their_own_activations(models):
    """Two solvers on one model (the pose window and a bake on a worker thread, two
    methods built from the shared shipped models) interleave their passes: a backward
    still reads the activation slopes of its own forward, and the matrices are made once."""
    from engine.solver.optimizer import dense_decoder

    a, b = dense_decoder(models.vae), dense_decoder(models.vae)
    assert a.weights is b.weights and a.forward_runs is b.forward_runs
    gen = np.random.default_rng(4)
    za, zb = (gen.standard_normal(24).astype(np.float32) for _ in range(2))
    g = gen.standard_normal(91).astype(np.float32)
    out, grad = a.forward(za), a.backward(g)
    again = a.forward(za)
    b.forward(zb)
    np.testing.assert_array_equal(a.backward(g), grad)
    np.testing.assert_array_equal(again, out)


@pytest.mark.parametrize("rule", ["adam", "sgd"])
def test_latent_update_matches_torch_optimizers(rule):
    gen = torch.Generator().manual_seed(2)
    z = torch.randn(24, generator=gen).requires_grad_(True)
    opt = (torch.optim.Adam([z], lr=0.05) if rule == "adam"
           else torch.optim.SGD([z], lr=0.3, momentum=0.5, nesterov=True))  # fmt: skip
    ours = LatentUpdate(rule, 0.05 if rule == "adam" else 0.3, momentum=0.0 if rule == "adam" else 0.5)
    mine = z.detach().numpy().copy()
    for _ in range(6):
        grad = torch.randn(24, generator=gen)
        z.grad = grad.clone()
        opt.step()
        mine = ours.step(mine, grad.numpy())
        np.testing.assert_allclose(mine, z.detach().numpy(), atol=1e-6)


@pytest.mark.parametrize("preset, mode", [("6", "realtime"), ("3-head-hands", "realtime"), ("6", "offline")])
def test_fast_and_reference_paths_give_the_same_poses(models, preset, mode):
    """Every frame is solved by both paths from the same state (latent history, carried
    Adam moments, previous root): positions within 1e-5 m, rotations within 1e-4 rad.

    The reference path starts each frame from a copy of the fast path's state, so what is
    compared is one frame's solve, not 16 frames of float32 round-off fed back through
    Adam (whose normalised steps amplify differences in near-zero gradients). Per frame
    the paths agree to about 5e-7 m. The cold first frame (30 full Adam steps from the
    mean latent) amplifies round-off most: up to 1.8e-4 m with shipped models at the
    six-tracker profile's rotation weight 0.01 (5.7e-7 m at 0.03; joint rotations then differ by up to 2.2e-3 rad), so it alone is held to
    5e-4 m and 5e-3 rad. Offline frames run 30 steps too: with the bank prior and the
    smoothing starting at frame 3, frame 12 of the offline run differs by
    4.0e-5 m / 1.2e-3 rad (its total loss by 8e-4 relative) while the other 14 agree to
    5e-7 m, so offline frames are held to 1e-4 m and 2e-3 rad; a wrong gradient term
    shows at the centimetre scale."""
    motion = load_motion(CLIP).slice(0, 16)
    tracking = simulate(motion, preset)
    fast = DragPoserMethod(models.vae, models.predictor, fast=True, mode=mode, iterations=10, max_iterations=30)
    fast.reset(motion.skeleton, motion.fps)
    for i in range(len(motion)):
        ref = copy.deepcopy(fast)
        ref.optimizer._fast = None  # the autograd path through the torch model
        a, b = fast.step(tracking.frame(i)), ref.step(tracking.frame(i))
        assert a.iterations == b.iterations
        pos_tol, rot_tol = (5e-4, 5e-3) if i == 0 else (1e-4, 2e-3) if mode == "offline" else (1e-5, 1e-4)
        np.testing.assert_allclose(a.positions, b.positions, atol=pos_tol)
        assert _angle(a.local_rot, b.local_rot).max() < rot_tol
        assert a.losses[-1]["total"] == pytest.approx(b.losses[-1]["total"], rel=1e-3, abs=1e-7)
    assert fast.optimizer._fast is not None


def _angle(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Rotation angle between unit quaternions, radians, accurate near zero (arccos of the
    dot product is not: float32 round-off alone reads as ~1e-3 rad there)."""
    d = Q.mul(Q.conjugate(Q.normalize(a)), Q.normalize(b))
    return 2.0 * np.arctan2(np.linalg.norm(d[..., 1:], axis=-1), np.abs(d[..., 0]))
