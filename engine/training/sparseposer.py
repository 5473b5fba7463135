"""Training of SparsePoser (Ponton et al. 2023, sec. 5.3) on prepared data.

Every step draws ``batch_size`` windows of ``window`` consecutive frames of one clip.
The generator is trained with the paper's L_DQ (MSE of the normalised root-space dual
quaternions of all joints). Ours, to fit a 2-core CPU: the loss covers only the last
``loss_frames`` frames of the window (the decoder then runs on that tail only, a quarter
of its cost), and the last frame counts ``1 + last_weight`` times, because the realtime
method (no future frames) uses only the last output frame, whose convolutions see zero
padding instead of future frames. The encoder still reads the whole window.
Then, with the generator frozen for that step (its output detached), the four limb
networks are trained on the last ``ik_frames`` frames of each window with
L_S + lambda L_Reg: L_S compares the end effector's root-space position (decimetres)
and rotation (quaternion difference) with the tracker's, L_Reg the limb's other joints
with the generator's pose (paper: lambda = 0.1).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import torch

from engine.kinematics.features import root_space_fk
from engine.models.loading import FORMAT_VERSION
from engine.models.sparseposer import LIMB_EE, LIMB_INDEX, SparsePoser, SparsePoserConfig
from engine.training.common import Distributed, config_dict, seed_everything
from engine.training.data import PoseData, load_split
from engine.training.loop import Schedule, average_gradients, run_epochs
from engine.training.sparseposer_ik import load_init, realtime_outputs

_NON_EE = sorted({j for limb in LIMB_INDEX for j in limb} - set(LIMB_EE))


@dataclass
class SparsePoserTrainConfig:
    window: int = 64
    channels: tuple[int, int, int] = (16, 32, 48)
    kernel: int = 3
    ik_hidden: int = 256
    last_weight: float = 1.0
    loss_frames: int = 16
    ik_frames: int = 8
    w_reg: float = 0.1
    batch_size: int = 32
    lr: float = 1e-3
    lr_final: float = 5e-5
    weight_decay: float = 1e-4
    steps_per_epoch: int = 200
    epochs: int = 100
    minutes: float = 35.0
    val_windows: int = 1024
    seed: int = 0
    max_clips: int = 0
    #: False: keep the generator of ``init`` and train only the limb networks, on the
    #: generator's realtime output at every training frame (engine/training/sparseposer_ik.py)
    train_generator: bool = True
    init: str = ""

    def model_config(self) -> SparsePoserConfig:
        return SparsePoserConfig(
            window=self.window, channels=self.channels, kernel=self.kernel, ik_hidden=self.ik_hidden
        )

    def schedule(self) -> Schedule:
        return Schedule(self.epochs, self.steps_per_epoch, self.minutes, self.lr, self.lr_final)


def window_starts(data: PoseData, window: int) -> torch.Tensor:
    """First frames of every window of ``window`` frames that stays inside one clip."""
    n = len(data)
    t = torch.arange(max(0, n - window + 1))
    return t[data.clip[t] == data.clip[t + window - 1]]


def gen_loss(
    model: SparsePoser, dq: torch.Tensor, offsets: torch.Tensor, last_weight: float, frames: int
) -> tuple[torch.Tensor, torch.Tensor]:
    """L_DQ over the last ``frames`` frames of windows ``dq (B, T, 22, 8)`` (raw), the
    last frame weighted up; also returns the generator output ``(B, frames, 22, 8)``."""
    out = model.generate(dq, offsets, tail=frames)
    per_frame = ((out - model.normalise(dq[:, -out.shape[1] :])) ** 2).mean(dim=(0, 2, 3))
    w = torch.ones_like(per_frame)
    w[-1] += last_weight
    return (per_frame * w).sum() / w.sum(), out


def ik_losses(model: SparsePoser, out: torch.Tensor, dq: torch.Tensor, offsets: torch.Tensor):
    """L_S and L_Reg for generator outputs ``out (B, 22, 8)`` (detached, normalised),
    true raw dq ``(B, 22, 8)`` and offsets ``(B, 22, 3)``."""
    local_gen = model.local_from_output(out)
    local_ik = model.refine(out, local_gen, offsets, dq)
    pos_ik, rot_ik = root_space_fk(local_ik, offsets)
    pos_gen, _ = root_space_fk(local_gen, offsets)
    true_pos, _ = root_space_fk(_true_local(model, dq), offsets)
    ee = list(LIMB_EE)
    l_pos = (((pos_ik[:, ee] - true_pos[:, ee]) * 10.0) ** 2).mean()
    true_rot = dq[:, ee, :4]
    dot = (rot_ik[:, ee] * true_rot).sum(-1, keepdim=True)
    l_rot = ((rot_ik[:, ee] - torch.where(dot < 0, -true_rot, true_rot)) ** 2).mean()
    l_reg = (((pos_ik[:, _NON_EE] - pos_gen[:, _NON_EE]) * 10.0) ** 2).mean()
    return l_pos + l_rot, l_reg


def _true_local(model: SparsePoser, dq: torch.Tensor) -> torch.Tensor:
    return model.local_from_output(model.normalise(dq))


def train_sparseposer(
    data_dir: Path, out_dir: Path, cfg: SparsePoserTrainConfig, resume: bool = False, progress: bool = True
) -> dict:
    """Train (or resume) SparsePoser; writes ``sparseposer.pt``, ``best.pt``, ``last.pt``, losses."""
    from engine.training.data import read_manifest

    ddp = Distributed("cpu")  # its data loop keeps every tensor in CPU memory
    seed_everything(cfg.seed)
    gen = torch.Generator().manual_seed(cfg.seed)
    manifest = read_manifest(data_dir)
    clips = cfg.max_clips or None
    train, val = load_split(data_dir, "train", clips), load_split(data_dir, "val", clips)
    model = SparsePoser(cfg.model_config(), manifest["stats"]).to(ddp.device)
    if cfg.init:
        load_init(model, cfg.init)
    opt_g = torch.optim.AdamW(model.generator.parameters(), lr=cfg.lr, weight_decay=cfg.weight_decay)
    opt_ik = torch.optim.AdamW(model.ik.parameters(), lr=cfg.lr, weight_decay=cfg.weight_decay)
    s_tr, s_va = window_starts(train, cfg.window), window_starts(val, cfg.window)
    s_va = s_va[torch.linspace(0, len(s_va) - 1, min(cfg.val_windows, len(s_va))).long()]
    ar = torch.arange(cfg.window)

    def step() -> dict[str, float]:
        pick = torch.randint(len(s_tr), (cfg.batch_size * ddp.world,), generator=gen)[ddp.rank :: ddp.world]
        idx = s_tr[pick][:, None] + ar
        dq, off = train.dq[idx], train.offsets[idx[:, 0]]
        lg, out = gen_loss(model, dq, off, cfg.last_weight, cfg.loss_frames)
        opt_g.zero_grad(set_to_none=True)
        lg.backward()
        average_gradients(ddp, model.generator.parameters())
        opt_g.step()
        k = cfg.ik_frames
        out = out[:, -k:].detach().reshape(-1, 22, 8)
        off_k = off[:, None].expand(-1, k, -1, -1).reshape(-1, 22, 3)
        l_s, l_reg = ik_losses(model, out, dq[:, -k:].reshape(-1, 22, 8), off_k)
        li = l_s + cfg.w_reg * l_reg
        opt_ik.zero_grad(set_to_none=True)
        li.backward()
        average_gradients(ddp, model.ik.parameters())
        opt_ik.step()
        return {"l_dq": lg.item(), "l_s": l_s.item(), "l_reg": l_reg.item()}

    if not cfg.train_generator:
        if not cfg.init:
            load_init(model, "")  # the clear error
        model.generator.requires_grad_(False)
        cached = realtime_outputs(model.eval(), train, progress=progress and ddp.main)

        def ik_step() -> dict[str, float]:  # the limb networks only
            b = torch.randint(len(train), (cfg.batch_size * ddp.world,), generator=gen)[ddp.rank :: ddp.world]
            l_s, l_reg = ik_losses(model, cached[b], train.dq[b], train.offsets[b])
            li = l_s + cfg.w_reg * l_reg
            opt_ik.zero_grad(set_to_none=True)
            li.backward()
            average_gradients(ddp, model.ik.parameters())
            opt_ik.step()
            return {"l_s": l_s.item(), "l_reg": l_reg.item()}

    def validate() -> dict[str, float]:
        return validate_sparseposer(model, val, s_va, cfg.window)

    def payload(meta: dict) -> dict:
        return {
            "format_version": FORMAT_VERSION,
            "kind": "sparseposer",
            "config": model.config.to_dict(),
            "state_dict": {k: v.detach().cpu() for k, v in model.state_dict().items()},
            "train_config": config_dict(cfg),
            "meta": meta,
        }

    meta = {"data_hash": manifest.get("hash"), "train_windows": len(s_tr)}
    optimizers, train_step = ([opt_g, opt_ik], step) if cfg.train_generator else ([opt_ik], ik_step)
    return run_epochs(
        "sparseposer",
        model,
        optimizers,
        train_step,
        validate,
        payload,
        cfg.schedule(),
        out_dir,
        ddp,
        gen,
        "val_pos_cm",
        resume,
        progress,
        meta,
    )


@torch.no_grad()
def validate_sparseposer(
    model: SparsePoser, data: PoseData, starts: torch.Tensor, window: int, batch: int = 256
) -> dict[str, float]:
    """Realtime figures on the last frame of each validation window (root space, cm):
    mean joint position error after the learned IK and of the generator alone, and the
    end effectors' error after the IK."""
    pos_err, gen_err, ee_err = [], [], []
    ar = torch.arange(window)
    for s in range(0, len(starts), batch):
        idx = starts[s : s + batch][:, None] + ar
        dq, off = data.dq[idx], data.offsets[idx[:, 0]]
        local_ik, local_gen = model(dq, off)
        true, _ = root_space_fk(_true_local(model, dq[:, -1]), off)
        p_ik, _ = root_space_fk(local_ik, off)
        p_gen, _ = root_space_fk(local_gen, off)
        pos_err.append((p_ik - true).norm(dim=-1).mean(-1))
        gen_err.append((p_gen - true).norm(dim=-1).mean(-1))
        ee_err.append((p_ik - true)[:, list(LIMB_EE)].norm(dim=-1).mean(-1))
    cm = lambda xs: 100.0 * float(torch.cat(xs).mean())  # noqa: E731
    return {"val_pos_cm": cm(pos_err), "val_gen_pos_cm": cm(gen_err), "val_ee_cm": cm(ee_err)}
