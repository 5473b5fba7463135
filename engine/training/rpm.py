"""Training of the Rolling Prediction Model (Barquero et al. 2025, Alg. 1, sec. 3.3).

Each step draws ``batch_size`` anchor frames t. The context holds the true poses
t-M..t-1 and the prediction window starts as the true poses t..t+W-1 (with probability
``p_cold`` both are the blank mean pose instead, so the model also learns to start from
nothing, as the method does at the first frame of a clip). Then, without gradients,
``fr ~ U(0, free_run)`` rolling steps run on the model's own outputs (free running); the
last step is taken with gradients and its window is compared with the true poses
(L1 on the root orientation, the local rotations, the joint positions in decimetres,
and the frame-to-frame differences of all three: the paper's six losses, weight 1).

**Tracking-loss augmentation.** For each sample and hand, with probability ``p_gap`` a
gap of 0.5-2 s (RPM's hand-tracking model, as ``engine.tracking.simulate``) is placed
at a random offset of the span the step reads, so transitions into and out of a loss
fall inside free running and inside the loss window.

Ours, to fit a 2-core CPU: ``free_run`` is 30 frames (0.5 s; the paper uses 1 s).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import pymotion.rotations.ortho6d_torch as o6
import torch

from engine.kinematics.fk import fk
from engine.models.loading import FORMAT_VERSION, load_rpm
from engine.models.rpm import (
    RPM,
    RPM_INDEX,
    RPMConfig,
    blank_pose,
    fk_root_space,
    roll,
    rolling_step,
    to_frame,
    track_features,
    yaw_matrix,
)
from engine.training.common import Distributed, config_dict, seed_everything, start_from
from engine.training.data import PoseData, load_split
from engine.training.loop import Schedule, average_gradients, run_epochs


@dataclass
class RPMTrainConfig:
    past_inputs: int = 10
    past_poses: int = 10
    window: int = 20
    hidden: int = 512
    blocks: int = 2
    free_run: int = 30
    p_gap: float = 0.5
    p_cold: float = 0.1
    batch_size: int = 64
    lr: float = 1e-3
    lr_final: float = 5e-5
    weight_decay: float = 1e-4
    steps_per_epoch: int = 100
    epochs: int = 100
    minutes: float = 35.0
    val_segments: int = 32
    val_frames: int = 240
    seed: int = 0
    max_clips: int = 0
    #: Start from the weights and normalisation of this RPM file instead of at random
    #: (fine-tuning, e.g. after a retargeting change); its architecture must match.
    init: str = ""

    def model_config(self) -> RPMConfig:
        return RPMConfig(self.past_inputs, self.past_poses, self.window, self.hidden, self.blocks)

    def schedule(self) -> Schedule:
        return Schedule(self.epochs, self.steps_per_epoch, self.minutes, self.lr, self.lr_final)


class Frames:
    """Per-frame world features of a split: poses (slot 0 world), trackers, heading frames."""

    def __init__(self, data: PoseData):
        pos, rot = fk(data.local_rot.double(), data.root_pos.double(), data.offsets.double())
        self.pose6 = o6.from_quat(torch.cat((rot[:, :1], data.local_rot[:, 1:].double()), 1)).float()
        idx = list(RPM_INDEX)
        self.sens_pos = pos[:, idx].float()
        self.sens_rot6 = o6.from_quat(rot[:, idx]).float()
        self.h = yaw_matrix(rot[:, idx[0]]).float()
        self.origin = self.sens_pos[:, 0] * torch.tensor([1.0, 1.0, 0.0])
        self.offsets = data.offsets
        self.clip = data.clip

    def __len__(self) -> int:
        return len(self.clip)

    def anchors(self, before: int, after: int) -> torch.Tensor:
        """Frames t with t-before .. t+after inside t's clip."""
        t = torch.arange(before, len(self) - after)
        return t[(self.clip[t - before] == self.clip[t]) & (self.clip[t + after] == self.clip[t])]

    def track(self, tau: torch.Tensor, flags: torch.Tensor, past: int) -> torch.Tensor:
        """Tracking features ``(B, past+1, 30)`` for current frames ``tau (B,)``; ``flags
        (B, past+1, 3)`` connected."""
        idx = tau[:, None] + torch.arange(-past, 1)
        return track_features(self.sens_pos[idx], self.sens_rot6[idx], flags, self.h[tau], self.origin[tau])


def stats(fr: Frames, cfg: RPMTrainConfig) -> dict:
    """Normalisation of canonical poses and tracking features (every 4th frame)."""
    t = torch.arange(cfg.past_inputs, len(fr), 4)
    pose = to_frame(fr.pose6[t][:, None], fr.h[t])[:, 0].flatten(1)
    tr = fr.track(t, torch.ones(len(t), 1, 3, dtype=torch.bool), 0)[:, 0]
    std = lambda x: x.std(0).clamp(min=1e-3)  # noqa: E731
    return {"pose_mean": pose.mean(0), "pose_std": std(pose), "track_mean": tr.mean(0), "track_std": std(tr)}


def gap_flags(b: int, span: int, p: float, gen: torch.Generator, fps: float = 60.0) -> torch.Tensor:
    """Connected flags ``(B, span, 3)``: head always, each hand lost for one 0.5-2 s gap
    at a random offset with probability ``p``."""
    flags = torch.ones(b, span, 3, dtype=torch.bool)
    for hand in (1, 2):
        has = torch.rand(b, generator=gen) < p
        length = torch.randint(int(0.5 * fps), int(2 * fps) + 1, (b,), generator=gen)
        start = torch.randint(0, span, (b,), generator=gen) - length // 2
        f = torch.arange(span)[None]
        lost = has[:, None] & (f >= start[:, None]) & (f < (start + length)[:, None])
        flags[:, :, hand] &= ~lost
    return flags


def pose_losses(pred6: torch.Tensor, true6: torch.Tensor, h: torch.Tensor, offsets: torch.Tensor) -> dict:
    """The six L1 losses between windows ``(B, W, 22, 3, 2)`` (world form), compared in
    the heading frame ``h``; ``offsets (B, 22, 3)``."""
    p, t = to_frame(pred6, h), to_frame(true6, h)
    off = offsets[:, None].expand(-1, p.shape[1], -1, -1)
    pp, tp = fk_root_space(p, off) * 10.0, fk_root_space(t, off) * 10.0
    d = lambda x: x[:, 1:] - x[:, :-1]  # noqa: E731
    out = {
        "ori": (p[:, :, 0] - t[:, :, 0]).abs().mean(),
        "rot": (p[:, :, 1:] - t[:, :, 1:]).abs().mean(),
        "pos": (pp - tp).abs().mean(),
    }
    out.update(
        {
            "v_ori": (d(p[:, :, 0]) - d(t[:, :, 0])).abs().mean(),
            "v_rot": (d(p[:, :, 1:]) - d(t[:, :, 1:])).abs().mean(),
            "v_pos": (d(pp) - d(tp)).abs().mean(),
        }
    )
    return out


def free_run(
    model: RPM,
    fr: Frames,
    t: torch.Tensor,
    steps: int,
    flags: torch.Tensor,
    cold: torch.Tensor,
    cfg: RPMTrainConfig,
    grad_last: bool = True,
):
    """Run ``steps`` rolling steps from anchors ``t`` (no gradients) and one more; returns
    the last prediction window ``(B, W, 22, 3, 2)`` and its frame ``tau``. ``flags (B, S, 3)``
    cover frames t-I .. t+steps; ``cold (B,)`` starts from blank poses."""
    m, w, past = cfg.past_poses, cfg.window, cfg.past_inputs
    ctx = fr.pose6[t[:, None] + torch.arange(-m, 0)]
    P = fr.pose6[t[:, None] + torch.arange(0, w)]
    blank = blank_pose(model, fr.h[t])
    ctx = torch.where(cold[:, None, None, None, None], blank[:, None].expand_as(ctx), ctx)
    P = torch.where(cold[:, None, None, None, None], blank[:, None].expand_as(P), P)
    with torch.no_grad():
        for i in range(steps):
            tau = t + i
            P = rolling_step(model, P, ctx, fr.track(tau, flags[:, i : i + past + 1], past), fr.h[tau])
            P, ctx = roll(P, ctx, blank_pose(model, fr.h[tau]))
    tau = t + steps
    with torch.set_grad_enabled(grad_last and torch.is_grad_enabled()):
        P = rolling_step(model, P, ctx, fr.track(tau, flags[:, steps : steps + past + 1], past), fr.h[tau])
    return P, tau


def train_rpm(data_dir: Path, out_dir: Path, cfg: RPMTrainConfig, resume: bool = False, progress: bool = True) -> dict:
    """Train (or resume) RPM; writes ``rpm.pt``, ``best.pt``, ``last.pt``, losses."""
    from engine.training.data import read_manifest

    ddp = Distributed("cpu")  # its data loop keeps every tensor in CPU memory
    seed_everything(cfg.seed)
    gen = torch.Generator().manual_seed(cfg.seed)
    manifest = read_manifest(data_dir)
    clips = cfg.max_clips or None
    train, val = Frames(load_split(data_dir, "train", clips)), Frames(load_split(data_dir, "val", clips))
    model = RPM(cfg.model_config(), stats(train, cfg)).to(ddp.device)
    if cfg.init:  # a resumed run then loads its own last.pt over it
        start_from(model, cfg.init, load_rpm)
    opt = torch.optim.AdamW(model.parameters(), lr=cfg.lr, weight_decay=cfg.weight_decay)
    before = max(cfg.past_inputs, cfg.past_poses)
    a_tr = train.anchors(before, cfg.free_run + cfg.window)
    a_va = val.anchors(cfg.past_inputs, cfg.val_frames + cfg.window)
    a_va = a_va[torch.linspace(0, len(a_va) - 1, min(cfg.val_segments, len(a_va))).long()]
    val_gen = torch.Generator().manual_seed(1234)
    val_flags = gap_flags(len(a_va), cfg.val_frames + cfg.past_inputs + 1, 1.0, val_gen)

    def step() -> dict[str, float]:
        b = cfg.batch_size
        pick = torch.randint(len(a_tr), (b * ddp.world,), generator=gen)[ddp.rank :: ddp.world]
        t = a_tr[pick]
        steps = int(torch.randint(0, cfg.free_run + 1, (1,), generator=gen))
        flags = gap_flags(len(t), steps + cfg.past_inputs + 1, cfg.p_gap, gen)
        cold = torch.rand(len(t), generator=gen) < cfg.p_cold
        P, tau = free_run(model, train, t, steps, flags, cold, cfg)
        true = train.pose6[tau[:, None] + torch.arange(cfg.window)]
        losses = pose_losses(P, true, train.h[tau], train.offsets[tau])
        loss = sum(losses.values())
        opt.zero_grad(set_to_none=True)
        loss.backward()
        average_gradients(ddp, model.parameters())
        opt.step()
        return {"loss": loss.item(), "pos": losses["pos"].item(), "v_pos": losses["v_pos"].item()}

    def validate() -> dict[str, float]:
        return validate_rpm(model, val, a_va, val_flags, cfg)

    def payload(meta: dict) -> dict:
        return {
            "format_version": FORMAT_VERSION,
            "kind": "rpm",
            "config": model.config.to_dict(),
            "state_dict": {k: v.detach().cpu() for k, v in model.state_dict().items()},
            "train_config": config_dict(cfg),
            "meta": meta,
        }

    meta = {"data_hash": manifest.get("hash"), "train_anchors": len(a_tr)}
    return run_epochs(
        "rpm",
        model,
        [opt],
        step,
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
def validate_rpm(model: RPM, fr: Frames, starts: torch.Tensor, flags: torch.Tensor, cfg: RPMTrainConfig) -> dict:
    """Cold-started rollouts of ``val_frames`` frames from each start, both hands losing
    tracking once; mean joint position error (cm, root-space poses) after the first
    second, overall and on the frames with a hand lost."""
    m, w, past = cfg.past_poses, cfg.window, cfg.past_inputs
    t = starts
    blank = blank_pose(model, fr.h[t])[:, None]
    P, ctx = blank.expand(-1, w, -1, -1, -1).clone(), blank.expand(-1, m, -1, -1, -1).clone()
    errs, lost = [], []
    for i in range(cfg.val_frames):
        tau = t + i
        P = rolling_step(model, P, ctx, fr.track(tau, flags[:, i : i + past + 1], past), fr.h[tau])
        if i >= 60:
            off = fr.offsets[tau]
            pred = fk_root_space(to_frame(P[:, :1], fr.h[tau]), off[:, None])[:, 0]
            true = fk_root_space(to_frame(fr.pose6[tau][:, None], fr.h[tau]), off[:, None])[:, 0]
            errs.append((pred - true).norm(dim=-1).mean(-1))
            lost.append(~flags[:, i + past, 1:].all(-1))
        P, ctx = roll(P, ctx, blank_pose(model, fr.h[tau]))
    e, lo = torch.stack(errs), torch.stack(lost)
    lost_err = float(e[lo].mean()) if lo.any() else float("nan")
    return {"val_pos_cm": 100.0 * float(e.mean()), "val_lost_pos_cm": 100.0 * lost_err}
