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
from engine.models.fused import DenseDecoder, Run, plan_runs
from engine.models.skeletal import level_sizes
from engine.motion.retarget import load_motion
from engine.solver import LatentUpdate
from engine.solver.optimizer import dense_decoder
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
        raw = torch.cat(
            (
                (vae.to_rot(x) + torch.tensor([1.0, 0, 0, 0])).flatten(1),
                vae.to_disp(x[:, 0]) * vae.disp_std + vae.disp_mean,
            ),
            dim=1,
        )
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
    for plan in (runs, one):
        np.testing.assert_array_equal(_rectangles(plan, w.shape), w)


def _rectangles(runs: list[Run], shape: tuple[int, int]) -> np.ndarray:
    """The matrix that ``runs`` store: their rectangles, zeros elsewhere (rows covered once)."""
    out, rows = np.zeros(shape, np.float32), np.zeros(shape[0], int)
    for r in runs:
        out[r.r0 : r.r1, r.c0 : r.c1] = r.w
        rows[r.r0 : r.r1] += 1
    assert (rows == 1).all()
    return out


def test_block_sparse_decoder_reads_less_and_equals_the_dense_products(models):
    dense = DenseDecoder(models.vae)
    total = sum(w.size for w in dense.weights)
    assert dense.stored_entries() < 0.6 * total  # 1.77 M entries, 0.64 M of them not zero
    for w, fr in zip(dense.weights, dense.forward_runs):
        np.testing.assert_array_equal(_rectangles(fr, w.shape), w)  # every non-zero entry is stored
    # the forward pass: the dense chain's products
    gen = np.random.default_rng(3)
    z = gen.standard_normal(24).astype(np.float32)
    x = z.astype(np.float64)
    for i, (w, b) in enumerate(zip(dense.weights, dense.biases)):
        x = w.astype(np.float64) @ x + b
        if i < len(dense.weights) - 1:
            x = np.where(x > 0, x, dense.slope * x)
    np.testing.assert_allclose(dense.forward(z), x, rtol=1e-4, atol=1e-5)
    # the backward pass reads the same rectangles transposed: the dense chain's gradient
    g = gen.standard_normal(91).astype(np.float32)
    expected = g.astype(np.float64)
    for i in range(len(dense.weights) - 1, -1, -1):
        if i < len(dense.weights) - 1:
            expected = expected * dense._gate[i]
        expected = expected @ dense.weights[i].astype(np.float64)
    np.testing.assert_allclose(dense.backward(g), expected, rtol=1e-4, atol=1e-5)


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
    opt = (
        torch.optim.Adam([z], lr=0.05) if rule == "adam" else torch.optim.SGD([z], lr=0.3, momentum=0.5, nesterov=True)
    )
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
    Adam moments, previous root): positions within 1e-5 m and rotations within 1e-4 rad,
    the first frame's cold solve and the offline mode's 30 steps included (the bundled
    clip's first 80 frames, presets 6, 6x3dof, 4 and 3-head-hands, realtime and offline,
    416 frames: at most 1.4e-6 m and 7.8e-6 rad); the total loss within 1e-3 relative.

    The reference path starts each frame from a copy of the fast path's state, so what is
    compared is one frame's solve, not 16 frames of float32 round-off fed back through Adam.

    Except where the two solves part at a kink of the decoder. LeakyReLU's slope jumps
    from 0.2 to 1 where a unit's pre-activation crosses zero; when an iterate puts a unit
    within round-off of zero the two paths can land on its two sides, their gradients
    then differ by that unit's whole share and Adam (normalised steps, carried second
    moments of 4e-7) spreads it: preset 6 offline with the head reached by the spine,
    frame 6, unit 185 of the first stage at -8.9e-8 on one path and +1.2e-7 on the other
    at step 11 (latents 1.1e-6 apart), gradients 2.5e-5 apart against 2e-3, and 2.3e-4 m
    at the end: two solves of one objective on two branches, as a rerun on another CPU
    could take. Such a frame is checked up to the kink instead: the latents agree until
    the step at which the paths' LeakyReLU branches part (1e-5; 1.2e-6 measured), and the
    units that part lie within 1e-6 of zero on both paths (1.5e-7 and 2.6e-8 measured at
    the two such frames met in those 416). A wrong gradient parts the paths before any kink
    does, far from it."""
    motion = load_motion(CLIP).slice(0, 16)
    tracking = simulate(motion, preset)
    fast = DragPoserMethod(models.vae, models.predictor, fast=True, mode=mode, iterations=10, max_iterations=30)
    fast.reset(motion.skeleton, motion.fps)
    dense = dense_decoder(models.vae)
    for i in range(len(motion)):
        ref = copy.deepcopy(fast)
        ref.optimizer._fast = None  # the autograd path through the torch model
        a, b = fast.step(tracking.frame(i)), ref.step(tracking.frame(i))
        path_a, path_b = fast.last_solve.solution.path, ref.last_solve.solution.path
        kink = _first_branch_split(dense, models.vae, path_a, path_b)
        if kink is not None:
            step, pre_a, pre_b = kink
            np.testing.assert_allclose(path_a[:step], path_b[:step], atol=1e-5, err_msg=f"frame {i}")
            assert np.abs(pre_a).max() < 1e-6 and np.abs(pre_b).max() < 1e-6, f"frame {i}: parted far from a kink"
            continue
        assert a.iterations == b.iterations
        np.testing.assert_allclose(a.positions, b.positions, atol=1e-5, err_msg=f"frame {i}")
        assert _angle(a.local_rot, b.local_rot).max() < 1e-4
        assert a.losses[-1]["total"] == pytest.approx(b.losses[-1]["total"], rel=1e-3, abs=1e-7)
    assert fast.optimizer._fast is not None


def _first_branch_split(dense: DenseDecoder, vae, path_a: np.ndarray, path_b: np.ndarray):
    """The first step at which the fast path's decoder (``dense`` at ``path_a``) and the
    reference's (``vae`` at ``path_b``) put some LeakyReLU unit on opposite sides of zero,
    with those units' pre-activations on each path; None when they never do."""
    for k in range(min(len(path_a), len(path_b))):
        dense.forward(path_a[k])
        for pa, pb in zip(dense.pre_activations(), _torch_pre_activations(vae, path_b[k])):
            parted = (pa > 0) != (pb > 0)
            if parted.any():
                return k, pa[parted], pb[parted]
    return None


def _torch_pre_activations(vae, z: np.ndarray) -> list[np.ndarray]:
    """The pre-activations of :meth:`PoseVAE.decode`'s LeakyReLUs at latent ``z (L,)``, in
    the fused decoder's order (:meth:`DenseDecoder.pre_activations`)."""
    with torch.no_grad():
        pre = [vae.from_latent(torch.from_numpy(np.asarray(z, np.float32))[None])]
        x = vae.act(pre[0]).reshape(1, level_sizes()[3], vae.config.channels[3])
        pre.append(vae.dec[0](torch.matmul(vae.unpool2, x)))
        pre.append(vae.dec[1](torch.matmul(vae.unpool1, vae.act(pre[-1]))))
        pre.append(vae.dec[2](torch.matmul(vae.unpool0, vae.act(pre[-1]))))
        pre.append(vae.dec[3](vae.act(pre[-1])))
    return [p.flatten(1)[0].numpy() for p in pre]


def _angle(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Rotation angle between unit quaternions, radians, accurate near zero (arccos of the
    dot product is not: float32 round-off alone reads as ~1e-3 rad there)."""
    d = Q.mul(Q.conjugate(Q.normalize(a)), Q.normalize(b))
    return 2.0 * np.arctan2(np.linalg.norm(d[..., 1:], axis=-1), np.abs(d[..., 0]))
