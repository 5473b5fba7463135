"""Training of the temporal predictor on latents of the trained VAE (DragPoser sec. 4.3, 5).

Training pairs follow Algorithm 1: for an anchor frame t the encoder sees the latents of
frames t - n*Wp .. t - n (stride n) with their conditioning, the decoder is fed the
latents of t, t+n, ..., t+n*(Wf-1) (teacher forcing, causal mask) and must output those of
t+n .. t+n*Wf. Loss: MSE in standardised latent units.

Limb noise regulariser (paper: "Gaussian noise ... applied to each limb with a 10%
probability"): latents are codes of whole poses, so we perturb *poses* and encode them.
For every training frame we precompute ``noise_copies`` noisy latents: each of the four
limbs (legs: hip..toe, arms: clavicle..wrist), with probability ``limb_noise_p``, has its
local joint rotations composed with a random rotation whose rotation-vector components
are drawn from N(0, std of that joint's rotation vector over the data). Inputs of a
sequence then use a noisy copy when any limb of that frame was perturbed; targets are
always clean.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass
from pathlib import Path

import pymotion.rotations.quat_torch as qt
import torch
from tqdm import tqdm

from engine import skeleton as sk
from engine.errors import UserError
from engine.kinematics import quaternion as Q
from engine.kinematics.features import encoder_input
from engine.models.loading import FORMAT_VERSION, load_checkpoint, load_predictor, load_vae
from engine.models.predictor import PredictorConfig, TemporalPredictor
from engine.models.vae import PoseVAE
from engine.training.common import CurveLog, Distributed, config_dict, save_checkpoint, seed_everything, start_from
from engine.training.data import PoseData, load_split

LIMBS = (
    ("lhip", "lknee", "lankle", "ltoe"),
    ("rhip", "rknee", "rankle", "rtoe"),
    ("lclavicle", "lshoulder", "lelbow", "lwrist"),
    ("rclavicle", "rshoulder", "relbow", "rwrist"),
)


@dataclass
class PredictorTrainConfig:
    d_model: int = 48
    heads: int = 4
    encoder_layers: int = 3
    decoder_layers: int = 3
    feedforward: int = 2048
    dropout: float = 0.1
    past: int = 16
    future: int = 16
    stride: int = 4
    limb_noise_p: float = 0.1
    noise_copies: int = 2
    #: Fraction of decoder input tokens (after the first) replaced by the model's own
    #: prediction of them from a gradient-free teacher-forced pass, so training sees the
    #: kind of input a free rollout feeds it (parallel scheduled sampling).
    self_feed: float = 0.0
    #: Checkpoint selection: ``val_mse`` (teacher-forced) or ``val_rollout_mse`` (free
    #: Wf-step rollout, what sparse sensor sets use).
    select: str = "val_mse"
    batch_size: int = 64
    lr: float = 1e-3
    lr_final: float = 5e-5
    weight_decay: float = 1e-4
    steps_per_epoch: int = 200
    epochs: int = 12
    minutes: float = 18.0
    seed: int = 0
    #: A predictor file to start from (fine-tuning after the VAE moved a little); its
    #: architecture must match. Its latent statistics are replaced by the new latents'.
    init: str = ""

    def model_config(self) -> PredictorConfig:
        return PredictorConfig(
            d_model=self.d_model,
            heads=self.heads,
            encoder_layers=self.encoder_layers,
            decoder_layers=self.decoder_layers,
            feedforward=self.feedforward,
            dropout=self.dropout,
            past=self.past,
            future=self.future,
            stride=self.stride,
        )


@torch.no_grad()
def encode_all(vae: PoseVAE, dq: torch.Tensor, batch: int = 8192) -> torch.Tensor:
    return torch.cat([vae.encode(dq[s : s + batch])[0] for s in range(0, dq.shape[0], batch)])


def conditioning(data: PoseData, stride: int) -> torch.Tensor:
    """(N, 9): root displacement summed over the last ``stride`` frames of the clip + heights."""
    disp = data.disp.clone()
    acc = disp.clone()
    start = torch.ones_like(data.has_next)
    start[1:] = data.clip[1:] != data.clip[:-1]
    for lag in range(1, stride):
        shifted = torch.zeros_like(disp)
        shifted[lag:] = disp[:-lag]
        same = torch.zeros(len(disp), dtype=torch.bool)
        same[lag:] = data.clip[lag:] == data.clip[:-lag]
        acc += shifted * same[:, None]
    return torch.cat((acc, data.heights), dim=-1)


@torch.no_grad()
def noisy_latents(vae: PoseVAE, data: PoseData, cfg: PredictorTrainConfig, gen: torch.Generator):
    """(K, N, L) latents of limb-perturbed poses and (K, N) flags of which frames changed."""
    rotvec = qt.to_scaled_angle_axis(data.rot[:, 1:].double()).float()  # (N, 21, 3)
    std = rotvec.std(dim=0)  # (21, 3)
    copies, flags = [], []
    for _ in range(cfg.noise_copies):
        rot = data.rot.clone()
        changed = torch.zeros(len(data), dtype=torch.bool)
        for limb in LIMBS:
            pick = torch.rand(len(data), generator=gen) < cfg.limb_noise_p
            changed |= pick
            for name in limb:
                j = sk.JOINT_INDEX[name]
                noise = torch.randn(int(pick.sum()), 3, generator=gen) * std[j - 1]
                dq = qt.from_scaled_angle_axis(noise.double()).float()
                rot[pick, j] = Q.normalize(Q.mul(rot[pick, j], dq))
        dq_in = encoder_input(rot, data.disp, data.offsets)
        copies.append(encode_all(vae, dq_in))
        flags.append(changed)
    return torch.stack(copies), torch.stack(flags)


def anchors(data: PoseData, cfg: PredictorTrainConfig) -> torch.Tensor:
    """Frames t with a full past (t - n*Wp) and future (t + n*Wf) inside their clip."""
    n = len(data)
    t = torch.arange(n)
    lo, hi = t - cfg.stride * cfg.past, t + cfg.stride * cfg.future
    ok = (lo >= 0) & (hi < n)
    ok[ok.clone()] &= (data.clip[lo[ok]] == data.clip[t[ok]]) & (data.clip[hi[ok]] == data.clip[t[ok]])
    return t[ok]


def make_batch(t, z, zc, cond, noisy, flags, cfg, gen):
    n, wp, wf = cfg.stride, cfg.past, cfg.future
    past_idx = t[:, None] + n * torch.arange(-wp, 0)[None]
    tok_idx = t[:, None] + n * torch.arange(0, wf)[None]
    tgt_idx = tok_idx + n

    def inputs(idx):
        clean = z[idx]
        if noisy is None:
            return clean
        k = torch.randint(noisy.shape[0], idx.shape, generator=gen)
        use = flags[k, idx]
        return torch.where(use[..., None], noisy[k, idx], clean)

    return inputs(past_idx), cond[past_idx], inputs(tok_idx), z[tgt_idx]


def _lr(cfg: PredictorTrainConfig, frac: float) -> float:
    return cfg.lr_final + (cfg.lr - cfg.lr_final) * 0.5 * (1 + math.cos(math.pi * min(1.0, frac)))


def train_predictor(
    data_dir: Path,
    vae_path: Path,
    out_dir: Path,
    cfg: PredictorTrainConfig,
    resume: bool = False,
    progress: bool = True,
    device: str = "auto",
) -> dict:
    """Train (or resume) the predictor; writes ``predictor.pt``, ``best.pt``, ``last.pt``, losses.

    ``device`` as :func:`engine.training.vae.train_vae`'s: the latents are made on the CPU,
    each step's batch moves to the device."""
    if cfg.select not in ("val_mse", "val_rollout_mse"):
        raise UserError(f"predictor setting 'select' must be val_mse or val_rollout_mse, got {cfg.select!r}")
    if not 0.0 <= cfg.self_feed <= 1.0:
        raise UserError(f"predictor setting 'self_feed' must be within [0, 1], got {cfg.self_feed!r}")
    ddp = Distributed(device)
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    seed_everything(cfg.seed)
    gen = torch.Generator().manual_seed(cfg.seed)
    vae, vae_meta = load_vae(vae_path)
    train, val = load_split(data_dir, "train"), load_split(data_dir, "val")
    z_tr, z_va = encode_all(vae, train.dq), encode_all(vae, val.dq)
    c_tr, c_va = conditioning(train, cfg.stride), conditioning(val, cfg.stride)
    noisy, flags = noisy_latents(vae, train, cfg, gen)
    model = TemporalPredictor(cfg.model_config()).to(ddp.device)
    if cfg.init:  # a resumed run then loads its own last.pt over it
        start_from(model, cfg.init, load_predictor)
    model.set_stats(z_tr.mean(0), z_tr.std(0), c_tr.mean(0), c_tr.std(0))
    # gradients are averaged across processes by hand (the model is called through two
    # methods, encode_past and decode_steps, which a DDP wrapper's forward would not see)
    opt = torch.optim.AdamW(model.parameters(), lr=cfg.lr, weight_decay=cfg.weight_decay)
    a_tr, a_va = anchors(train, cfg), anchors(val, cfg)
    log, best, start, minutes_before, step_total = CurveLog(out_dir), float("inf"), 0, 0.0, 0
    if resume and (out_dir / "last.pt").is_file():
        ck = load_checkpoint(out_dir / "last.pt", "checkpoint")
        model.load_state_dict(ck["state_dict"])
        opt.load_state_dict(ck["optimizer"])
        start, minutes_before, best, step_total = ck["epoch"], ck["minutes"], ck["best"], ck["step"]
        log = CurveLog(out_dir, ck["curve"])
        gen.set_state(ck["gen"])
    total = cfg.epochs * cfg.steps_per_epoch
    t0 = time.monotonic()
    meta = {
        "vae": str(vae_path),
        "vae_data_hash": vae_meta.get("data_hash"),
        "train_anchors": len(a_tr),
        "device": str(ddp.device),
    }
    for epoch in range(start, cfg.epochs):
        model.train()
        run = 0.0
        bar = tqdm(
            range(cfg.steps_per_epoch),
            desc=f"predictor epoch {epoch + 1}/{cfg.epochs}",
            disable=not (progress and ddp.main),
            leave=False,
        )
        for step in bar:
            minutes = minutes_before + (time.monotonic() - t0) / 60
            frac = max(step_total / total, minutes / cfg.minutes if cfg.minutes else 0.0)
            for g in opt.param_groups:
                g["lr"] = _lr(cfg, frac)
            pick = torch.randint(len(a_tr), (cfg.batch_size * ddp.world,), generator=gen)
            t = a_tr[pick[ddp.rank :: ddp.world]]
            past, cond, tokens, target = (
                x.to(ddp.device) for x in make_batch(t, z_tr, None, c_tr, noisy, flags, cfg, gen)
            )
            memory = model.encode_past(past, cond)
            if cfg.self_feed > 0:
                tokens = self_fed(model, tokens, memory, cfg.self_feed, gen)
            pred = model.decode_steps(tokens, memory)
            loss = (((pred - target) / model.z_std) ** 2).mean()
            opt.zero_grad(set_to_none=True)
            loss.backward()
            if ddp.world > 1:
                for p in model.parameters():
                    if p.grad is not None:
                        torch.distributed.all_reduce(p.grad)
                        p.grad /= ddp.world
            opt.step()
            step_total += 1
            run += float(loss.detach())
            if step % 10 == 0:
                bar.set_postfix(mse=f"{run / (step + 1):.4f}")
        minutes = minutes_before + (time.monotonic() - t0) / 60
        row = {"epoch": epoch + 1, "train_mse": ddp.mean(run / cfg.steps_per_epoch), "minutes": round(minutes, 2)}
        if ddp.main:
            row.update(validate(model, z_va, c_va, a_va, cfg))
            log.append(row)
            if progress:
                tqdm.write(" ".join(f"{k}={v:.4g}" for k, v in row.items()))
            meta.update(
                epochs=epoch + 1,
                minutes=round(minutes, 2),
                val_mse=row["val_mse"],
                val_rollout_mse=row["val_rollout_mse"],
            )
            if row[cfg.select] < best:
                best = row[cfg.select]
                save_checkpoint(out_dir / "best.pt", payload(model, cfg, dict(meta)))
            save_checkpoint(
                out_dir / "last.pt",
                {
                    "state_dict": model.state_dict(),
                    "optimizer": opt.state_dict(),
                    "epoch": epoch + 1,
                    "minutes": minutes,
                    "best": best,
                    "step": step_total,
                    "curve": log.rows,
                    "gen": gen.get_state(),
                },
            )
        ddp.barrier()
        if cfg.minutes and minutes >= cfg.minutes:
            break
    if ddp.main:
        meta["finished"] = True
        save_checkpoint(out_dir / "predictor.pt", payload(model, cfg, meta))
    ddp.close()
    return meta


def self_fed(
    model: TemporalPredictor, tokens: torch.Tensor, memory: torch.Tensor, p: float, gen: torch.Generator
) -> torch.Tensor:
    """``tokens (B, T, L)`` with each token after the first replaced, with probability
    ``p``, by the model's own (gradient-free, teacher-forced) prediction of it."""
    with torch.no_grad():
        own = model.decode_steps(tokens, memory.detach())[:, :-1]  # predictions of tokens 1..T-1
    pick = torch.rand(tokens.shape[:2], generator=gen) < p
    pick[:, 0] = False
    pick = pick.to(tokens.device)
    shifted = torch.cat((tokens[:, :1], own), dim=1)
    return torch.where(pick[..., None], shifted, tokens)


@torch.no_grad()
def validate(model: TemporalPredictor, z, cond, anchors_, cfg, limit: int = 2048) -> dict:
    """Teacher-forced MSE and the MSE of a free autoregressive rollout over Wf steps."""
    model.eval()
    idx = anchors_[torch.linspace(0, len(anchors_) - 1, min(limit, len(anchors_))).long()]
    dev = next(model.parameters()).device
    past, c, tokens, target = (x.to(dev) for x in make_batch(idx, z, None, cond, None, None, cfg, None))
    tf = (((model.decode_steps(tokens, model.encode_past(past, c)) - target) / model.z_std) ** 2).mean()
    roll = model.predict(past, c, tokens[:, 0], cfg.future)
    ro = (((roll - target) / model.z_std) ** 2).mean()
    return {"val_mse": float(tf), "val_rollout_mse": float(ro)}


def payload(model: TemporalPredictor, cfg: PredictorTrainConfig, meta: dict) -> dict:
    return {
        "format_version": FORMAT_VERSION,
        "kind": "predictor",
        "config": model.config.to_dict(),
        "state_dict": {k: v.detach().cpu() for k, v in model.state_dict().items()},
        "train_config": config_dict(cfg),
        "meta": meta,
    }
