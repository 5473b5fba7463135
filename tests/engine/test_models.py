"""Pose VAE, temporal predictor and weights loading: shapes, losses, gradients, errors."""

from __future__ import annotations

import numpy as np
import pytest
import torch

from engine import skeleton as sk
from engine.errors import ModelFileError
from engine.kinematics import quaternion as Q
from engine.kinematics.features import encoder_input, pose_from_motion, root_space_fk
from engine.models.loading import load_models, load_predictor, load_vae
from engine.models.predictor import PredictorConfig, TemporalPredictor
from engine.models.skeletal import SkeletalLinear, level_edges, level_sizes, neighbour_mask
from engine.models.vae import PoseVAE, VAEConfig, pose_distance
from engine.training.vae import VAEObjective, VAETrainConfig, weights_payload

TINY = VAEConfig(channels=(8, 8, 12, 16))


def _batch(motion, n=16):
    lr = torch.as_tensor(motion.local_rot[: n + 1], dtype=torch.float32)
    rp = torch.as_tensor(motion.root_pos[: n + 1], dtype=torch.float32)
    off = torch.as_tensor(motion.skeleton.offsets, dtype=torch.float32).expand(n + 1, -1, -1)
    rot, disp = pose_from_motion(lr, rp)
    pos, _ = root_space_fk(rot, off)
    dq = encoder_input(rot, disp, off)
    return {
        "dq": dq[:n],
        "rot": rot[:n],
        "disp": disp[:n],
        "pos": pos[:n],
        "offsets": off[:n],
        "rot_next": rot[1:],
        "disp_next": disp[1:],
    }


def test_skeletal_mask_keeps_far_joints_out():
    mask = neighbour_mask(sk.NUM_JOINTS, level_edges()[0], 2)
    layer = SkeletalLinear(mask, 8, 4)
    x = torch.randn(2, sk.NUM_JOINTS, 8)
    y0 = layer(x)
    x2 = x.clone()
    x2[:, sk.JOINT_INDEX["lwrist"]] += 5.0
    y1 = layer(x2)
    assert torch.allclose(y0[:, sk.JOINT_INDEX["root"]], y1[:, sk.JOINT_INDEX["root"]])
    assert not torch.allclose(y0[:, sk.JOINT_INDEX["lelbow"]], y1[:, sk.JOINT_INDEX["lelbow"]])


@pytest.mark.parametrize("level, c_in, c_out", [(0, 8, 32), (1, 48, 64), (3, 96, 64)])
def test_skeletal_block_batch_pass_equals_the_per_node_pass(level, c_in, c_out):
    """A batch of BLOCKS_FROM poses or more runs as block-sparse products: the same outputs
    and the same gradients (weights, bias, input) as the per-node pass a few poses take."""
    from engine.models import skeletal

    mask = neighbour_mask(level_sizes()[level], level_edges()[level], 2)
    layer = SkeletalLinear(mask, c_in, c_out)
    with torch.no_grad():
        layer.bias.normal_()
    x = torch.randn(skeletal.BLOCKS_FROM, layer.n, c_in, requires_grad=True)
    grads = []
    for small in (False, True):
        layer.zero_grad()
        x.grad = None
        y = torch.cat([layer(x[i : i + 1]) for i in range(len(x))]) if small else layer(x)
        (y * torch.linspace(-1, 1, y.numel()).reshape(y.shape)).sum().backward()
        grads.append((y.detach(), layer.weight.grad.clone(), layer.bias.grad.clone(), x.grad.clone()))
    for blocked, per_node in zip(*grads):
        torch.testing.assert_close(blocked, per_node, rtol=1e-5, atol=1e-5)
    assert grads[0][1].abs().sum() > 0


@pytest.mark.parametrize(
    "level, unpooled, call_cost", [(0, False, 0.0), (0, True, 0.0), (2, True, 0.0), (0, False, 1e9)]
)
def test_skeletal_block_products_first_and_second_order_gradients(monkeypatch, level, unpooled, call_cost):
    """The block-sparse products' gradients, and the gradients of those (the continuity
    loss's second order), against finite differences in float64; an unpooling read in
    place gives what the per-node pass gives on the unpooled input. Call cost 0: a
    rectangle per node and input range (several add to one node's outputs); 1e9: one."""
    from engine.models import skeletal

    monkeypatch.setattr(skeletal, "BLOCKS_FROM", 2)
    monkeypatch.setattr(skeletal, "BLOCK_CALL_COST", call_cost)
    n = level_sizes()[level]
    source = skeletal.unpool_source(skeletal.POOL_GROUPS[level]) if unpooled else None
    layer = SkeletalLinear(neighbour_mask(n, level_edges()[level], 2), 2, 3).double()
    gen = torch.Generator().manual_seed(level)
    x = torch.randn(3, n if source is None else max(source) + 1, 2, dtype=torch.float64, generator=gen)
    w = layer.weight.detach().clone().requires_grad_(True)
    b = torch.randn(n, 3, dtype=torch.float64, generator=gen).requires_grad_(True)

    def f(x, w, b):
        return torch.func.functional_call(layer, {"weight": w, "bias": b}, (x, source))

    x.requires_grad_(True)
    assert torch.autograd.gradcheck(f, (x, w, b))
    assert torch.autograd.gradgradcheck(f, (x, w, b))
    unpooled_x = x if source is None else x[:, list(source)]
    per_node = torch.cat([layer(unpooled_x[i : i + 1]) for i in range(3)])
    torch.testing.assert_close(f(x, w, layer.bias), per_node, rtol=1e-12, atol=1e-12)
    plan = layer.layout(source, x.device).plan
    assert (len(plan.spans) > n) if call_cost == 0 else (len(plan.spans) == 1)


def test_vae_shapes_and_unit_quaternions(synthetic_motion):
    vae = PoseVAE(TINY)
    b = _batch(synthetic_motion)
    mu, logvar = vae.encode(b["dq"])
    assert mu.shape == logvar.shape == (16, 24)
    rot, disp = vae.decode(mu)
    assert rot.shape == (16, 22, 4) and disp.shape == (16, 3)
    assert torch.allclose(rot.norm(dim=-1), torch.ones(16, 22), atol=1e-5)
    assert (rot[..., 0] >= 0).all()


def test_loss_terms_zero_where_they_must_be(synthetic_motion):
    b = _batch(synthetic_motion)
    assert torch.allclose(pose_distance(b["rot"], b["disp"], b["rot"], b["disp"], torch.ones(3)), torch.zeros(16))
    # sign-invariant: -q is the same rotation
    assert torch.allclose(pose_distance(b["rot"], b["disp"], -b["rot"], b["disp"], torch.ones(3)), torch.zeros(16))
    pos, _ = root_space_fk(b["rot"], b["offsets"])
    assert torch.allclose(pos, b["pos"], atol=1e-6)
    mu, logvar = torch.zeros(4, 24), torch.zeros(4, 24)
    assert float((-0.5 * (1 + logvar - mu**2 - logvar.exp()).sum(-1)).mean()) == 0.0


def test_every_term_positive_and_gradients_reach_every_parameter(synthetic_motion):
    torch.manual_seed(0)
    vae = PoseVAE(TINY)
    out = VAEObjective(vae, VAETrainConfig())(_batch(synthetic_motion))
    for k in ("rot", "fk", "kl", "cont", "total"):
        assert torch.isfinite(out[k]) and out[k] > 0, k
    out["total"].backward()
    for name, p in vae.named_parameters():
        assert p.grad is not None and p.grad.abs().sum() > 0, name


def test_predictor_shapes_and_autoregression():
    cfg = PredictorConfig(feedforward=64)
    model = TemporalPredictor(cfg).eval()
    past, cond, first = torch.randn(3, 16, 24), torch.randn(3, 16, 9), torch.randn(3, 24)
    out = model.predict(past, cond, first, 5)
    assert out.shape == (3, 5, 24)
    # the first prediction does not depend on how many steps are asked for (causal decoder)
    assert torch.allclose(model.predict(past, cond, first, 1)[:, 0], out[:, 0], atol=1e-5)


def _save(path, payload):
    torch.save(payload, path)
    return path


def test_loading_checks_the_file(tmp_path):
    vae = PoseVAE(TINY)
    good = _save(tmp_path / "vae.pt", weights_payload(vae, VAETrainConfig(), {"epochs": 1}))
    loaded, meta = load_vae(good)
    assert meta["epochs"] == 1 and not loaded.training
    with pytest.raises(ModelFileError, match="not found"):
        load_vae(tmp_path / "missing.pt")
    (tmp_path / "junk.pt").write_text("not a torch file")
    with pytest.raises(ModelFileError, match="junk.pt"):
        load_vae(tmp_path / "junk.pt")
    with pytest.raises(ModelFileError, match="expected 'predictor'"):
        load_predictor(good)
    bad = weights_payload(vae, VAETrainConfig(), {})
    bad["config"]["channels"] = [8, 8, 12, 32]
    with pytest.raises(ModelFileError, match="do not fit"):
        load_vae(_save(tmp_path / "shape.pt", bad))
    old = weights_payload(vae, VAETrainConfig(), {})
    old["format_version"] = 99
    with pytest.raises(ModelFileError, match="format_version"):
        load_vae(_save(tmp_path / "old.pt", old))
    with pytest.raises(ModelFileError, match="not found"):
        load_models(good, tmp_path / "nopred.pt")


def test_autoencoder_method_reconstructs_through_the_vae(synthetic_motion):
    from engine.methods import get_method, run_method
    from engine.tracking import simulate

    vae = PoseVAE(TINY).eval()
    method = get_method("autoencoder", vae=vae)
    motion, results = run_method(
        method, simulate(synthetic_motion, "6"), synthetic_motion.skeleton, progress=False, reference=synthetic_motion
    )
    assert len(motion) == len(synthetic_motion)
    np.testing.assert_allclose(motion.root_pos, synthetic_motion.root_pos)
    assert results[0].latent.shape == (24,)
    assert np.isfinite(motion.positions()).all()
    # untrained: poses differ from the ground truth, but are valid rotations
    assert np.allclose(np.linalg.norm(motion.local_rot, axis=-1), 1.0, atol=1e-5)
    assert Q.angle(motion.local_rot[:, 1:], synthetic_motion.local_rot[:, 1:]).mean() > 0


def test_shipped_models_are_read_once_and_again_when_their_file_is_replaced(tmp_path, monkeypatch):
    """``load_default_models`` shares one frozen copy of the shipped models per process;
    each caller's ``meta`` is its own; a file renamed over the shipped one is read again,
    and a missing one is an error naming it."""
    import shutil

    from engine.models import loading

    vae, pred = tmp_path / "vae.pt", tmp_path / "predictor.pt"
    shutil.copy(loading.DEFAULT_VAE, vae)
    shutil.copy(loading.DEFAULT_PREDICTOR, pred)
    monkeypatch.setattr(loading, "DEFAULT_VAE", vae)
    monkeypatch.setattr(loading, "DEFAULT_PREDICTOR", pred)
    monkeypatch.setattr(loading, "_SHIPPED", {})  # the process's own shipped models stay out of this
    first, again = loading.load_default_models(), loading.load_default_models()
    assert again.vae is first.vae and again.predictor is first.predictor is not None
    assert not first.vae.training and not any(p.requires_grad for p in first.vae.parameters())
    again.vae_meta["epochs"] = -1
    assert loading.load_default_models().vae_meta.get("epochs") != -1
    shutil.copy(pred, tmp_path / "new.pt")
    (tmp_path / "new.pt").replace(pred)
    replaced = loading.load_default_models()
    assert replaced.predictor is not first.predictor and replaced.vae is not first.vae
    vae.unlink()
    with pytest.raises(ModelFileError, match="vae.pt"):
        loading.load_default_models()
