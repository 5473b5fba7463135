"""Training of the pose VAE (DragPoser sec. 4.3 and 5, "Training details").

Loss = w_rot L_Q + w_fk L_FK + w_kl L_KLD + w_cont L_C with the paper's weights
(1, 100, 0.001, 1). L_C, the continuity loss, takes one gradient step in latent space
from pose i towards pose i+1 and asks the decoder to land on pose i+1 (paper eqs. 11-13);
the inner gradient is taken with ``create_graph=True`` so the step itself is trained.
Every term is computed inside one ``forward`` so DistributedDataParallel sees exactly
one forward and one backward per step.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass
from pathlib import Path

import torch
from torch import nn
from tqdm import tqdm

from engine.errors import UserError
from engine.kinematics import quaternion as Q
from engine.kinematics.features import root_space_positions
from engine.models.loading import load_checkpoint, load_vae
from engine.models.skeletal import reusing_rectangles
from engine.models.vae import PoseVAE, VAEConfig, pose_distance
from engine.training.common import (
    CurveLog,
    Distributed,
    config_dict,
    on_device,
    save_checkpoint,
    seed_everything,
    start_from,
)
from engine.training.data import PoseData, load_split, read_manifest
from engine.training.vae_anchor import DecoderAnchor
from engine.training.vae_batches import batch_of

FORMAT_VERSION = 1


@dataclass
class VAETrainConfig:
    """Everything a VAE run depends on; every field can be set with ``--set key=value``."""

    latent: int = 24
    channels: tuple[int, int, int, int] = (32, 48, 64, 96)
    w_rot: float = 1.0
    w_fk: float = 100.0
    w_kl: float = 0.001
    w_cont: float = 1.0
    batch_size: int = 256
    lr: float = 1e-3
    lr_final: float = 5e-5
    weight_decay: float = 1e-4
    epochs: int = 30
    minutes: float = 45.0
    seed: int = 0
    val_max_frames: int = 20000
    #: Limb-mix augmentation: probability that a training pose gets one limb (arm or leg
    #: chain) from another random training frame, so the model sees new combinations of
    #: limb poses (the validation dances are new combinations of familiar limb poses).
    limb_mix: float = 0.0
    #: Proportion augmentation: every bone's length is scaled by a factor drawn uniformly
    #: in ``1 +- bone_scale`` per training pose (one factor per bone, shared by its left and
    #: right copies), so the encoder meets performers of other builds than the training
    #: subjects'. Encoder input and target positions are recomputed by FK.
    bone_scale: float = 0.0
    #: Stop after this many epochs in this invocation (0: no limit); resume continues the
    #: same schedule, so a run can be trained in chunks.
    stop_after: int = 0
    #: Stop when the validation position error has not improved for this many epochs
    #: (0: never); the run's final ``vae.pt`` is then the best epoch's weights. With
    #: ``minutes = 0`` and many ``epochs`` this trains to convergence, not to a budget.
    patience: int = 0
    #: Start from the weights of this VAE file instead of at random (fine-tuning, e.g.
    #: after a retargeting change); its architecture must match the settings'. The
    #: prepared data's normalisation statistics replace the file's.
    init: str = ""
    #: False: keep the encoder of ``init`` fixed and train only the decoder. Every real
    #: pose then keeps the latent the shipped encoder gives it, so a temporal predictor,
    #: pose bank and latent map trained on those latents stay valid; only what the
    #: decoder draws from each latent improves.
    train_encoder: bool = True
    #: Weight of the decoder anchor (engine/training/vae_anchor.py; 0: off): latents drawn
    #: ``anchor_low``-``anchor_high`` standard units around each pose's encoder latent
    #: decode as the ``anchor`` VAE (empty: ``init``) decodes them.
    w_anchor: float = 0.0
    anchor: str = ""
    anchor_low: float = 0.5
    anchor_high: float = 1.5

    def model_config(self) -> VAEConfig:
        return VAEConfig(latent=self.latent, channels=(*self.channels,))  # a tuple (a JSON config gives a list)


class VAEObjective(nn.Module):
    """Wraps the VAE; ``forward`` returns the weighted total and each term."""

    def __init__(self, vae: PoseVAE, cfg: VAETrainConfig, anchor: DecoderAnchor | None = None):
        super().__init__()
        self.vae, self.cfg, self.anchor = vae, cfg, anchor

    def forward(self, b: dict[str, torch.Tensor]) -> dict[str, torch.Tensor]:
        with reusing_rectangles(self.vae):  # the decoder runs twice: its weights laid out once
            return self._terms(b)

    def _terms(self, b: dict[str, torch.Tensor]) -> dict[str, torch.Tensor]:
        vae, cfg = self.vae, self.cfg
        if cfg.train_encoder:
            mu, logvar = vae.encode(b["dq"])
            z = mu + torch.randn_like(mu) * torch.exp(0.5 * logvar)
        else:  # a fixed encoder: its latents are data, and the continuity term's gradient needs a leaf
            with torch.no_grad():
                mu, logvar = vae.encode(b["dq"])
            z = (mu + torch.randn_like(mu) * torch.exp(0.5 * logvar)).requires_grad_(True)
        rot, disp = vae.decode(z)
        l_rot = pose_distance(rot, disp, b["rot"], b["disp"], vae.disp_std).mean()
        pos = root_space_positions(rot, b["offsets"])
        l_fk = ((pos - b["pos"]) ** 2).mean()
        l_kl = (-0.5 * (1 + logvar - mu**2 - logvar.exp()).sum(-1)).mean()
        out = {"rot": l_rot, "fk": l_fk, "kl": l_kl}
        total = cfg.w_rot * l_rot + cfg.w_fk * l_fk + cfg.w_kl * l_kl
        if self.anchor is not None:
            out["anchor"] = self.anchor(vae, mu, b["offsets"])
            total = total + cfg.w_anchor * out["anchor"]
        if cfg.w_cont > 0:
            inner = pose_distance(rot, disp, b["rot_next"], b["disp_next"], vae.disp_std).sum()
            (grad,) = torch.autograd.grad(inner, z, create_graph=True)
            rot2, disp2 = vae.decode(z - grad)
            l_c = pose_distance(rot2, disp2, b["rot_next"], b["disp_next"], vae.disp_std).mean()
            out["cont"] = l_c
            total = total + cfg.w_cont * l_c
        out["total"] = total
        return out


@torch.no_grad()
def reconstruction_error(vae: PoseVAE, data: PoseData, max_frames: int | None = None, batch: int = 4096) -> dict:
    """Encode (mean) -> decode every frame; mean joint position error (cm, root space) and
    mean local joint rotation error (degrees, joints 1-21) against the ground truth."""
    vae.eval()
    dev = next(vae.parameters()).device
    n = len(data) if max_frames is None else min(len(data), max_frames)
    pos_err, rot_err, count = 0.0, 0.0, 0
    for s in range(0, n, batch):
        idx = torch.arange(s, min(n, s + batch))
        mu, _ = vae.encode(data.dq[idx].to(dev))
        rot, _ = vae.decode(mu)
        pos = root_space_positions(rot, data.offsets[idx].to(dev))
        pos_err += torch.linalg.vector_norm(pos - data.pos[idx].to(dev), dim=-1).mean(-1).sum().item()
        rot_err += Q.angle(rot[:, 1:], data.rot[idx, 1:].to(dev)).mean(-1).sum().item()
        count += idx.numel()
    return {"val_pos_cm": 100.0 * pos_err / count, "val_rot_deg": math.degrees(rot_err / count)}


def state_hash(model: nn.Module) -> str:
    """SHA-256 of a model's parameters and buffers (to compare processes or runs)."""
    import hashlib

    h = hashlib.sha256()
    for k, v in sorted(model.state_dict().items()):
        h.update(k.encode())
        h.update(v.detach().cpu().contiguous().numpy().tobytes())
    return h.hexdigest()


def cosine_lr(cfg: VAETrainConfig, step_fraction: float, minutes: float) -> float:
    """Cosine decay from ``lr`` to ``lr_final`` over whichever runs out first: the planned
    steps or the wall-clock budget (so a run cut by ``--minutes`` still ends annealed).
    Runs are deterministic when the budget does not bind."""
    frac = step_fraction
    if cfg.minutes:
        frac = max(frac, minutes / cfg.minutes)
    frac = min(1.0, frac)
    return cfg.lr_final + (cfg.lr - cfg.lr_final) * 0.5 * (1.0 + math.cos(math.pi * frac))


def weights_payload(vae: PoseVAE, cfg: VAETrainConfig, meta: dict) -> dict:
    return {
        "format_version": FORMAT_VERSION,
        "kind": "vae",
        "config": vae.config.to_dict(),
        "state_dict": {k: v.detach().cpu() for k, v in vae.state_dict().items()},
        "train_config": config_dict(cfg),
        "meta": meta,
    }


def train_vae(
    data_dir: Path,
    out_dir: Path,
    cfg: VAETrainConfig,
    resume: bool = False,
    progress: bool = True,
    device: str = "auto",
) -> dict:
    """Train (or resume) a VAE; writes ``last.pt``, ``best.pt``, ``vae.pt``, ``losses.csv/png``.

    ``device``: a :data:`engine.training.common.DEVICES` name (``auto``: CUDA when torch
    sees it). Returns the final metadata (epochs, minutes, validation errors, device)."""
    ddp = Distributed(device)
    out_dir = Path(out_dir)
    if ddp.main:
        out_dir.mkdir(parents=True, exist_ok=True)
    seed_everything(cfg.seed)
    manifest = read_manifest(data_dir)
    train = load_split(data_dir, "train")
    val = load_split(data_dir, "val")
    vae = PoseVAE(cfg.model_config(), manifest["stats"]).to(ddp.device)
    if cfg.init:  # a resumed run then loads its own last.pt over it
        start_from(vae, cfg.init, load_vae)
        vae.set_stats(manifest["stats"])
    if not cfg.train_encoder:
        if not cfg.init:
            raise UserError("train_encoder = false needs init = a VAE weights file whose encoder is kept")
        for module in (*vae.enc, vae.to_mu, vae.to_logvar):
            module.requires_grad_(False)
    anchor = None
    if cfg.w_anchor > 0:
        if not (cfg.anchor or cfg.init):
            raise UserError("w_anchor > 0 needs anchor (or init) = the VAE weights file to anchor the decoder to")
        anchor = DecoderAnchor.from_file(
            cfg.anchor or cfg.init, cfg.anchor_low, cfg.anchor_high, cfg.w_rot, cfg.w_fk
        ).to(ddp.device)
    objective: nn.Module = VAEObjective(vae, cfg, anchor)
    if ddp.world > 1:
        objective = nn.parallel.DistributedDataParallel(objective)
    # the fused kernel: one pass over all parameters instead of a dozen tensor ops per tensor
    trained = [p for p in vae.parameters() if p.requires_grad]
    opt = torch.optim.AdamW(trained, lr=cfg.lr, weight_decay=cfg.weight_decay, fused=True)
    pairs = torch.nonzero(train.has_next).squeeze(1)
    steps_per_epoch = max(1, len(pairs) // (cfg.batch_size * ddp.world))
    total_steps = steps_per_epoch * cfg.epochs
    start_epoch, minutes_before, best, global_step, best_epoch, stalled = 0, 0.0, float("inf"), 0, 0, False
    log = CurveLog(out_dir)
    last = out_dir / "last.pt"
    if resume and last.is_file():
        ck = load_checkpoint(last, "checkpoint")
        vae.load_state_dict(ck["state_dict"])
        opt.load_state_dict(ck["optimizer"])
        start_epoch, minutes_before, best = ck["epoch"], ck["minutes"], ck["best"]
        best_epoch = ck.get("best_epoch", start_epoch)
        global_step = ck["step"]
        log = CurveLog(out_dir, ck["curve"])
        torch.set_rng_state(ck["rng"])
    t0 = time.monotonic()
    meta: dict = {
        "data_hash": manifest.get("hash"),
        "train_frames": len(train),
        "val_frames": len(val),
        "device": str(ddp.device),
    }
    for epoch in range(start_epoch, cfg.epochs):
        vae.train()
        gen = torch.Generator().manual_seed(cfg.seed * 1000 + epoch)
        perm = pairs[torch.randperm(len(pairs), generator=gen)]
        gen = ddp.own_stream(gen, cfg.seed * 1000 + epoch)
        sums_t: torch.Tensor | None = None
        bar = tqdm(
            range(steps_per_epoch),
            desc=f"vae epoch {epoch + 1}/{cfg.epochs}",
            disable=not (progress and ddp.main),
            leave=False,
        )
        for step in bar:
            lo = (step * ddp.world + ddp.rank) * cfg.batch_size
            idx = perm[lo : lo + cfg.batch_size]
            minutes = minutes_before + (time.monotonic() - t0) / 60.0
            for group in opt.param_groups:
                group["lr"] = cosine_lr(cfg, global_step / total_steps, minutes)
            batch = batch_of(train, idx, cfg.limb_mix, gen, pairs, cfg.bone_scale)
            losses = objective(on_device(batch, ddp.device))
            opt.zero_grad(set_to_none=True)
            losses["total"].backward()
            opt.step()
            global_step += 1
            # summed on the device: one host sync per progress update, not one per loss and step
            terms = torch.stack([v.detach() for v in losses.values()])
            sums_t = terms if sums_t is None else sums_t + terms
            if step % 10 == 0:
                bar.set_postfix({k: f"{v / (step + 1):.2e}" for k, v in zip(losses, sums_t.tolist())})
        assert sums_t is not None  # an epoch has a step at least
        sums = dict(zip(losses, sums_t.tolist()))
        row = {"epoch": epoch + 1, **{k: ddp.mean(v / steps_per_epoch) for k, v in sums.items()}}
        minutes = minutes_before + (time.monotonic() - t0) / 60.0
        if ddp.main:
            row.update(reconstruction_error(vae, val, cfg.val_max_frames))
            row["minutes"] = round(minutes, 2)
            log.append(row)
            if progress:
                tqdm.write(" ".join(f"{k}={v:.4g}" if isinstance(v, float) else f"{k}={v}" for k, v in row.items()))
            meta.update(
                epochs=epoch + 1,
                minutes=round(minutes, 2),
                val_pos_cm=row["val_pos_cm"],
                val_rot_deg=row["val_rot_deg"],
            )
            if row["val_pos_cm"] < best:
                best, best_epoch = row["val_pos_cm"], epoch + 1
                meta["best_epoch"] = best_epoch
                save_checkpoint(out_dir / "best.pt", weights_payload(vae, cfg, dict(meta)))
            save_checkpoint(
                last,
                {
                    "state_dict": vae.state_dict(),
                    "optimizer": opt.state_dict(),
                    "step": global_step,
                    "epoch": epoch + 1,
                    "minutes": minutes,
                    "best": best,
                    "best_epoch": best_epoch,
                    "curve": log.rows,
                    "rng": torch.get_rng_state(),
                },
            )
        ddp.barrier()
        if cfg.patience and epoch + 1 - best_epoch >= cfg.patience:
            stalled = True
            if ddp.main and progress:
                tqdm.write(
                    f"validation has not improved for {cfg.patience} epochs (best: epoch {best_epoch}): stopping"
                )
            break
        if cfg.stop_after and epoch + 1 - start_epoch >= cfg.stop_after and epoch + 1 < cfg.epochs:
            return meta
        if cfg.minutes and minutes >= cfg.minutes:
            if ddp.main and progress:
                tqdm.write(f"time budget of {cfg.minutes} min reached after epoch {epoch + 1}")
            break
    if ddp.world > 1:  # every rank records its weights: they must agree
        (out_dir / f"weights_rank{ddp.rank}.sha256").write_text(state_hash(vae) + "\n")
    if ddp.main:
        meta["finished"] = True
        if stalled:  # the final file is the best epoch's weights, with the whole run's record
            meta["stopped"] = f"no improvement for {cfg.patience} epochs"
            vae.load_state_dict(load_vae(out_dir / "best.pt")[0].state_dict())
        save_checkpoint(out_dir / "vae.pt", weights_payload(vae, cfg, meta))
    ddp.close()
    return meta
