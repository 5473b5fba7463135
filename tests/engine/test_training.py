"""Training on tiny synthetic data: determinism, resume, predictor, and a 2-process DDP run."""

from __future__ import annotations

import os
import subprocess
import sys

import numpy as np
import pytest
import torch

from engine import skeleton as sk
from engine.config import load_config
from engine.data.prepare import prepare
from engine.errors import UserError
from engine.kinematics import quaternion as Q
from engine.motion.bvh import save_motion_bvh
from engine.motion.clip import Motion
from engine.training.vae import VAETrainConfig, state_hash, train_vae

TINY_VAE = ["channels=[8, 8, 12, 16]", "batch_size=32", "val_max_frames=200", "minutes=0.0"]


def _motion(seed: int, frames: int = 80) -> Motion:
    rng = np.random.default_rng(seed)
    t = np.arange(frames) / 60.0
    amp = rng.uniform(0.05, 0.4, size=(sk.NUM_JOINTS, 3))
    phase = rng.uniform(0, 2 * np.pi, size=(sk.NUM_JOINTS, 3))
    aa = amp[None] * np.sin(2 * np.pi * rng.uniform(0.5, 1.5) * t[:, None, None] + phase[None])
    ang = np.linalg.norm(aa, axis=-1)
    rot = Q.from_axis_angle(aa / np.maximum(ang[..., None], 1e-9), ang)
    root = np.stack([0.2 * t, -1.0 * t, 0.95 + 0.02 * np.sin(4 * np.pi * t)], axis=-1)
    return Motion(rot, root, sk.Skeleton.canonical(), 60.0, f"synth{seed}")


@pytest.fixture(scope="module")
def tiny_data(tmp_path_factory):
    root = tmp_path_factory.mktemp("tiny")
    for i in range(9):
        save_motion_bvh(root / "src" / "synth" / f"{i:02d}.bvh", _motion(i))
    prepare([root / "src"], root / "prepared", progress=False)
    return root / "prepared"


def _cfg(**kw) -> VAETrainConfig:
    return load_config(VAETrainConfig, None, TINY_VAE, **kw)


def _weights(path):
    return torch.load(path, map_location="cpu", weights_only=True)["state_dict"]


def _same(a, b) -> bool:
    wa, wb = _weights(a), _weights(b)
    return all(torch.equal(wa[k], wb[k]) for k in wa)


@pytest.fixture(scope="module")
def run_a(tiny_data, tmp_path_factory):
    out = tmp_path_factory.mktemp("run_a")
    meta = train_vae(tiny_data, out, _cfg(epochs=2, seed=3), progress=False)
    return out, meta


def test_vae_training_writes_its_outputs_and_is_deterministic(tiny_data, run_a, tmp_path):
    out, meta = run_a
    for name in ("vae.pt", "best.pt", "last.pt", "losses.csv", "losses.png"):
        assert (out / name).is_file(), name
    assert meta["epochs"] == 2 and np.isfinite(meta["val_pos_cm"])
    assert (out / "losses.csv").read_text().count("\n") == 3  # header + 2 epochs
    train_vae(tiny_data, tmp_path / "b", _cfg(epochs=2, seed=3), progress=False)
    assert _same(out / "vae.pt", tmp_path / "b/vae.pt"), "same seed, same data: same weights"
    train_vae(tiny_data, tmp_path / "c", _cfg(epochs=1, seed=4), progress=False)
    wc, wa = _weights(tmp_path / "c/vae.pt"), _weights(out / "best.pt")
    assert not all(torch.equal(wa[k], wc[k]) for k in wa), "the seed must matter"


def test_resume_continues_exactly(tiny_data, run_a, tmp_path):
    train_vae(tiny_data, tmp_path / "r", _cfg(epochs=2, seed=3, stop_after=1), progress=False)
    assert torch.load(tmp_path / "r/last.pt", weights_only=False)["epoch"] == 1
    assert not (tmp_path / "r/vae.pt").exists()
    train_vae(tiny_data, tmp_path / "r", _cfg(epochs=2, seed=3), resume=True, progress=False)
    assert torch.load(tmp_path / "r/last.pt", weights_only=False)["epoch"] == 2
    assert _same(run_a[0] / "vae.pt", tmp_path / "r/vae.pt"), "stop + resume must equal the straight run"


def test_patience_stops_a_run_whose_validation_stalls(tiny_data, run_a, tmp_path):
    """With nothing learnt (lr 0) validation never improves on epoch 1: ``patience=2``
    ends the run after epoch 3 of 10, and the final file is the best epoch's."""
    cfg = _cfg(init=str(run_a[0] / "vae.pt"), epochs=10, seed=5, lr=0.0, lr_final=0.0, patience=2)
    meta = train_vae(tiny_data, tmp_path / "p", cfg, progress=False)
    assert meta["epochs"] == 3 and meta["best_epoch"] == 1 and "2 epochs" in meta["stopped"]
    assert (tmp_path / "p/losses.csv").read_text().count("\n") == 4
    assert _same(tmp_path / "p/best.pt", tmp_path / "p/vae.pt")
    straight = train_vae(tiny_data, tmp_path / "q", _cfg(epochs=2, seed=3, patience=5), progress=False)
    assert straight["epochs"] == 2 and "stopped" not in straight


def test_init_starts_from_a_vae_file_and_checks_its_architecture(tiny_data, run_a, tmp_path):
    frozen = dict(epochs=1, seed=5, lr=0.0, lr_final=0.0, weight_decay=0.0)
    train_vae(tiny_data, tmp_path / "i", _cfg(init=str(run_a[0] / "vae.pt"), **frozen), progress=False)
    assert _same(run_a[0] / "vae.pt", tmp_path / "i/vae.pt"), "no learning: the init weights come out unchanged"
    train_vae(tiny_data, tmp_path / "n", _cfg(**frozen), progress=False)
    assert not _same(run_a[0] / "vae.pt", tmp_path / "n/vae.pt"), "without init the start is random"
    with pytest.raises(UserError, match="init .*architecture"):
        train_vae(tiny_data, tmp_path / "x", _cfg(init=str(run_a[0] / "vae.pt"), latent=5, **frozen), progress=False)


def test_a_fixed_encoder_keeps_every_latent_and_trains_the_decoder(tiny_data, run_a, tmp_path):
    init = run_a[0] / "vae.pt"
    train_vae(tiny_data, tmp_path / "d", _cfg(init=str(init), epochs=1, seed=5, train_encoder=False), progress=False)
    before, after = _weights(init), _weights(tmp_path / "d/vae.pt")
    encoder = [k for k in before if k.startswith(("enc.", "to_mu.", "to_logvar."))]
    decoder = [k for k in before if k.startswith(("dec.", "from_latent.", "to_rot.", "to_disp."))]
    assert encoder and decoder
    assert all(torch.equal(before[k], after[k]) for k in encoder), "the encoder must not move"
    assert not all(torch.equal(before[k], after[k]) for k in decoder), "the decoder must learn"
    with pytest.raises(UserError, match="train_encoder = false needs init"):
        train_vae(tiny_data, tmp_path / "e", _cfg(epochs=1, train_encoder=False), progress=False)


def test_the_decoder_anchor_holds_the_latents_no_pose_encodes_to(tiny_data, run_a, tmp_path):
    """A decoder fine-tune with the anchor on stays closer to the reference decoder away
    from the encoder's latents than the same run without it; the anchor of a decoder to
    itself is zero, and an anchor with no reference file is refused."""
    from engine.models.loading import load_vae
    from engine.training.vae_anchor import DecoderAnchor

    init = run_a[0] / "vae.pt"
    reference, _ = load_vae(init)
    for name, weight in (("free", 0.0), ("held", 50.0)):
        cfg = _cfg(init=str(init), epochs=1, seed=5, train_encoder=False, lr=3e-3, w_anchor=weight)
        train_vae(tiny_data, tmp_path / name, cfg, progress=False)
    z = 2.0 * torch.randn(256, reference.config.latent, generator=torch.Generator().manual_seed(0))
    with torch.no_grad():
        ref_rot = reference.decode(z)[0]
        drift = {
            n: (load_vae(tmp_path / n / "vae.pt")[0].decode(z)[0] - ref_rot).abs().mean().item()
            for n in ("free", "held")
        }
    assert drift["held"] < 0.5 * drift["free"], drift
    offsets = torch.as_tensor(sk.Skeleton.canonical().offsets, dtype=torch.float32).expand(4, -1, -1)
    with torch.no_grad():
        own = DecoderAnchor(reference, 0.5, 1.5, 1.0, 100.0)(
            reference, torch.zeros(4, reference.config.latent), offsets
        )
    assert own.item() == pytest.approx(0.0, abs=1e-10)
    with pytest.raises(UserError, match="w_anchor > 0 needs anchor"):
        train_vae(tiny_data, tmp_path / "e", _cfg(epochs=1, w_anchor=1.0), progress=False)


@pytest.mark.parametrize("model", ["vae", "predictor"])
def test_resume_never_runs_code_from_a_planted_checkpoint(tiny_data, run_a, tmp_path, model):
    from engine.errors import ModelFileError
    from engine.training.predictor import PredictorTrainConfig, train_predictor
    from tests.engine.test_checkpoint_security import plant

    out, marker = tmp_path / "run", tmp_path / "pwned"
    out.mkdir()
    plant(out / "last.pt", marker)
    with pytest.raises(ModelFileError, match="refused"):
        if model == "vae":
            train_vae(tiny_data, out, _cfg(epochs=1, seed=3), resume=True, progress=False)
        else:
            cfg = PredictorTrainConfig(
                d_model=16,
                heads=2,
                encoder_layers=1,
                decoder_layers=1,
                feedforward=32,
                past=4,
                future=4,
                stride=2,
                batch_size=8,
                steps_per_epoch=1,
                epochs=1,
            )
            train_predictor(tiny_data, run_a[0] / "vae.pt", out, cfg, resume=True, progress=False)
    assert not marker.exists(), "resuming ran code from the checkpoint"


def test_config_file_and_overrides(tmp_path):

    f = tmp_path / "c.toml"
    f.write_text("epochs = 7\nlr = 0.01\n")
    cfg = load_config(VAETrainConfig, f, ["batch_size=8", "channels=[4, 4, 4, 4]"], lr=0.02)
    assert (cfg.epochs, cfg.batch_size, cfg.lr, cfg.channels) == (7, 8, 0.02, (4, 4, 4, 4))
    with pytest.raises(UserError, match="nope"):
        load_config(VAETrainConfig, None, ["nope=1"])
    with pytest.raises(UserError, match="batch_size"):
        load_config(VAETrainConfig, None, ["batch_size=abc"])


def test_predictor_trains_on_vae_latents(tiny_data, run_a, tmp_path):
    from engine.models.loading import load_predictor
    from engine.training.predictor import PredictorTrainConfig, train_predictor

    cfg = PredictorTrainConfig(
        d_model=16,
        heads=2,
        encoder_layers=1,
        decoder_layers=1,
        feedforward=32,
        past=4,
        future=4,
        stride=2,
        batch_size=8,
        steps_per_epoch=5,
        epochs=2,
        minutes=0.0,
    )
    meta = train_predictor(tiny_data, run_a[0] / "vae.pt", tmp_path / "pred", cfg, progress=False)
    assert meta["epochs"] == 2 and np.isfinite(meta["val_mse"]) and np.isfinite(meta["val_rollout_mse"])
    model, pmeta = load_predictor(tmp_path / "pred/predictor.pt")
    assert pmeta["finished"] and model.config.past == 4


def test_predictor_init_starts_from_a_predictor_file(tiny_data, run_a, tmp_path):
    from engine.models.loading import load_predictor
    from engine.training.predictor import PredictorTrainConfig, train_predictor

    small = dict(
        d_model=16,
        heads=2,
        encoder_layers=1,
        decoder_layers=1,
        feedforward=32,
        past=4,
        future=4,
        stride=2,
        batch_size=8,
        steps_per_epoch=3,
        epochs=1,
        minutes=0.0,
    )
    train_predictor(tiny_data, run_a[0] / "vae.pt", tmp_path / "a", PredictorTrainConfig(**small), progress=False)
    frozen = dict(small, lr=0.0, lr_final=0.0, weight_decay=0.0, seed=7)
    init = str(tmp_path / "a/predictor.pt")
    train_predictor(
        tiny_data, run_a[0] / "vae.pt", tmp_path / "i", PredictorTrainConfig(**frozen, init=init), progress=False
    )
    a, b = (
        load_predictor(tmp_path / "a/predictor.pt")[0].state_dict(),
        load_predictor(tmp_path / "i/predictor.pt")[0].state_dict(),
    )
    assert all(torch.equal(a[k], b[k]) for k in a), (
        "no learning: the init weights (and the same latents' stats) come out unchanged"
    )
    train_predictor(tiny_data, run_a[0] / "vae.pt", tmp_path / "n", PredictorTrainConfig(**frozen), progress=False)
    c = load_predictor(tmp_path / "n/predictor.pt")[0].state_dict()
    assert not all(torch.equal(a[k], c[k]) for k in a), "without init the start is random"
    with pytest.raises(UserError, match="init .*architecture"):
        train_predictor(
            tiny_data,
            run_a[0] / "vae.pt",
            tmp_path / "x",
            PredictorTrainConfig(**dict(frozen, d_model=8), init=init),
            progress=False,
        )


@pytest.mark.slow
def test_two_process_ddp_ranks_agree(tiny_data, tmp_path):
    out = tmp_path / "ddp"
    env = {**os.environ, "OMP_NUM_THREADS": "1"}
    cmd = [
        sys.executable,
        "-m",
        "torch.distributed.run",
        "--standalone",
        "--nproc_per_node=2",
        "-m",
        "engine.cli.main",
        "train",
        "vae",
        "--data",
        str(tiny_data),
        "--out",
        str(out),
        "--epochs",
        "1",
        "--quiet",
    ] + [a for s in TINY_VAE for a in ("--set", s)]
    proc = subprocess.run(cmd, env=env, capture_output=True, text=True, timeout=240)
    assert proc.returncode == 0, proc.stderr[-2000:]
    h0 = (out / "weights_rank0.sha256").read_text()
    h1 = (out / "weights_rank1.sha256").read_text()
    assert h0 == h1
    from engine.models.loading import load_vae

    vae, _ = load_vae(out / "vae.pt")
    assert state_hash(vae) + "\n" == h0


def test_limb_mix_swaps_one_limb_and_recomputes_the_features(tiny_data):
    from engine.kinematics.features import encoder_input, root_space_fk
    from engine.training.data import load_split
    from engine.training.vae_batches import LIMBS, batch_of

    data = load_split(tiny_data, "train")
    pairs = torch.nonzero(data.has_next).squeeze(1)
    idx = pairs[:64]
    plain = batch_of(data, idx)
    mixed = batch_of(data, idx, 1.0, torch.Generator().manual_seed(0), pairs)
    changed = ~torch.isclose(mixed["rot"], plain["rot"], atol=1e-6).all(-1)  # (B, J)
    limb_sets = [set(j) for j in LIMBS]
    for row in changed:
        joints = set(torch.nonzero(row).squeeze(1).tolist())
        assert any(joints <= limb for limb in limb_sets), f"changed joints {joints} are not one limb"
    assert changed.any(-1).float().mean() > 0.8, "with limb_mix=1 (almost) every pose is mixed"
    # the successor's limb comes from the donor's successor: where rot changed, so did rot_next
    changed_next = ~torch.isclose(mixed["rot_next"], plain["rot_next"], atol=1e-6).all(-1)
    assert bool((changed_next | ~changed).all())
    pos, _ = root_space_fk(mixed["rot"], mixed["offsets"])
    assert torch.allclose(mixed["pos"], pos) and not torch.allclose(mixed["pos"], plain["pos"])
    assert torch.allclose(mixed["dq"], encoder_input(mixed["rot"], mixed["disp"], mixed["offsets"]))
    assert torch.equal(batch_of(data, idx, 0.0, None, pairs)["rot"], plain["rot"])


def test_the_device_auto_is_the_cpu_here_with_the_same_weights_and_cuda_is_refused(tiny_data, tmp_path):
    """``--device auto`` trains where ``cpu`` does on a machine without CUDA, to the same
    weights; ``cuda`` there is a clear error, before any work."""
    import pytest
    import torch

    from engine.errors import UserError
    from engine.models.loading import load_vae
    from engine.training.common import pick_device
    from engine.training.vae import state_hash, train_vae

    if torch.cuda.is_available():
        pytest.skip("a CUDA device is present: auto would take it")
    a = train_vae(tiny_data, tmp_path / "auto", _cfg(epochs=1, seed=5), progress=False, device="auto")
    c = train_vae(tiny_data, tmp_path / "cpu", _cfg(epochs=1, seed=5), progress=False, device="cpu")
    assert a["device"] == c["device"] == "cpu"
    assert state_hash(load_vae(tmp_path / "auto" / "vae.pt")[0]) == state_hash(load_vae(tmp_path / "cpu" / "vae.pt")[0])
    with pytest.raises(UserError, match="--device cuda: torch sees no CUDA device"):
        pick_device("cuda")
    with pytest.raises(UserError, match="--device must be one of auto, cpu, cuda"):
        pick_device("tpu")


def test_each_rank_draws_its_own_augmentation_after_the_shared_permutation(tiny_data):
    """Ranks share the epoch's permutation, but a rank drawing the same stream as rank 0
    would give its half of the batch rank 0's donor limbs and bone scales."""
    from engine.training.common import Distributed
    from engine.training.data import load_split
    from engine.training.vae_batches import batch_of

    data = load_split(tiny_data, "train")
    idx = torch.nonzero(data.has_next).squeeze(1)[:64]
    ddp = Distributed("cpu")
    shared = torch.Generator().manual_seed(3)
    assert ddp.own_stream(shared, 3) is shared  # a single process draws what it always drew
    with torch.random.fork_rng():
        torch.manual_seed(0)
        before = torch.rand(4)
        ddp.rank = 1
        own = ddp.own_stream(torch.Generator().manual_seed(3), 3)
        torch.manual_seed(0)
        ddp.own_stream(torch.Generator().manual_seed(3), 3)
        assert not torch.equal(torch.rand(4), before)  # the encoder's noise too
    pairs = torch.nonzero(data.has_next).squeeze(1)
    rank0 = batch_of(data, idx, 1.0, torch.Generator().manual_seed(3), pairs, 0.15)
    rank1 = batch_of(data, idx, 1.0, own, pairs, 0.15)
    assert not torch.allclose(rank0["offsets"], rank1["offsets"])
    assert not torch.allclose(rank0["rot"], rank1["rot"])
