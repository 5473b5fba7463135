"""The epoch loop shared by ``train sparseposer`` and ``train rpm``: cosine learning rate
over the epochs or the minutes budget (whichever ends first, so a run cut by the budget
still ends annealed), a tqdm bar with the live losses, per-epoch validation, ``best.pt``
/ ``last.pt`` (for ``--resume``) / the final file, and ``losses.csv``/``losses.png``.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import torch
from tqdm import tqdm

from engine.models.loading import load_checkpoint
from engine.training.common import CurveLog, Distributed, save_checkpoint


@dataclass
class Schedule:
    """What the loop needs from a trainer's config."""

    epochs: int
    steps_per_epoch: int
    minutes: float
    lr: float
    lr_final: float


def cosine_lr(s: Schedule, frac: float) -> float:
    return s.lr_final + (s.lr - s.lr_final) * 0.5 * (1 + math.cos(math.pi * min(1.0, frac)))


def average_gradients(ddp: Distributed, params) -> None:
    """Average gradients across ``torchrun`` processes (no-op for one process)."""
    if ddp.world == 1:
        return
    for p in params:
        if p.grad is not None:
            torch.distributed.all_reduce(p.grad)
            p.grad /= ddp.world


def run_epochs(
    name: str,
    model: torch.nn.Module,
    optimizers: Sequence[torch.optim.Optimizer],
    step: Callable[[], dict[str, float]],
    validate: Callable[[], dict[str, float]],
    payload: Callable[[dict], dict],
    sched: Schedule,
    out_dir: Path,
    ddp: Distributed,
    gen: torch.Generator,
    best_key: str,
    resume: bool = False,
    progress: bool = True,
    meta: dict | None = None,
) -> dict:
    """Train until ``sched.epochs`` or the minutes budget; returns the final metadata.

    ``step()`` runs one optimisation step (backward and ``optimizer.step`` included) and
    returns its losses; ``validate()`` returns validation figures (rank 0 only);
    ``payload(meta)`` builds the weights-file dict. ``best_key`` (lower is better) picks
    ``best.pt``. The minutes budget is checked before every step: when it runs out the
    epoch ends early (it is still validated and saved). The final ``OUT/<name>.pt`` is
    written when the loop ends, by epochs or by budget; its ``meta['finished']`` is True.
    """
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    meta = dict(meta or {})
    log, best, start, minutes_before, step_total = CurveLog(out_dir), float("inf"), 0, 0.0, 0
    if resume and (out_dir / "last.pt").is_file():
        ck = load_checkpoint(out_dir / "last.pt", "checkpoint")  # never runs code (weights_only)
        model.load_state_dict(ck["state_dict"])
        for opt, state in zip(optimizers, ck["optimizers"]):
            opt.load_state_dict(state)
        start, minutes_before, best, step_total = ck["epoch"], ck["minutes"], ck["best"], ck["step"]
        log = CurveLog(out_dir, ck["curve"])
        gen.set_state(ck["gen"])
        meta.update(ck.get("meta", {}))
    total = max(1, sched.epochs * sched.steps_per_epoch)
    t0 = time.monotonic()
    minutes = minutes_before
    for epoch in range(start, sched.epochs):
        if sched.minutes and minutes >= sched.minutes:
            break
        model.train()
        sums: dict[str, float] = {}
        bar = tqdm(
            range(sched.steps_per_epoch),
            desc=f"{name} epoch {epoch + 1}/{sched.epochs}",
            disable=not (progress and ddp.main),
            leave=False,
        )
        done = 0
        for i in bar:
            minutes = minutes_before + (time.monotonic() - t0) / 60
            if sched.minutes and minutes >= sched.minutes and done:
                break  # the budget ends inside this epoch: validate and save what we have
            frac = max(step_total / total, minutes / sched.minutes if sched.minutes else 0.0)
            for opt in optimizers:
                for g in opt.param_groups:
                    g["lr"] = cosine_lr(sched, frac)
            losses = step()
            step_total += 1
            done += 1
            for k, v in losses.items():
                sums[k] = sums.get(k, 0.0) + v
            if i % 10 == 0:
                bar.set_postfix({k: f"{v / (i + 1):.4f}" for k, v in sums.items()})
        minutes = minutes_before + (time.monotonic() - t0) / 60
        row: dict[str, Any] = {"epoch": epoch + 1, "minutes": round(minutes, 2)}
        row.update({k: ddp.mean(v / max(1, done)) for k, v in sums.items()})
        if ddp.main:
            model.eval()
            with torch.no_grad():
                row.update(validate())
            log.append(row)
            if progress:
                tqdm.write(" ".join(f"{k}={v:.4g}" for k, v in row.items()))
            meta.update(
                {k: v for k, v in row.items() if k.startswith("val_")}, epochs=epoch + 1, minutes=round(minutes, 2)
            )
            if row[best_key] < best:
                best = row[best_key]
                meta["best_epoch"] = epoch + 1
                save_checkpoint(out_dir / "best.pt", payload(dict(meta)))
            save_checkpoint(
                out_dir / "last.pt",
                {
                    "state_dict": model.state_dict(),
                    "optimizers": [o.state_dict() for o in optimizers],
                    "epoch": epoch + 1,
                    "minutes": minutes,
                    "best": best,
                    "step": step_total,
                    "curve": log.rows,
                    "gen": gen.get_state(),
                    "meta": meta,
                },
            )
        ddp.barrier()
    if ddp.main:
        meta["finished"], meta["steps"] = True, step_total
        save_checkpoint(out_dir / f"{name}.pt", payload(meta))
    ddp.close()
    return meta
