"""What every training command shares: config files with overrides, seeding, process
groups for ``torchrun``, checkpoints and loss curves."""

from __future__ import annotations

import csv
import dataclasses
import io
import os
import random
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
import torch
import torch.distributed as dist

from engine.atomic import atomic_path, write_bytes
from engine.errors import UserError

if TYPE_CHECKING:
    from engine.models.predictor import TemporalPredictor
    from engine.models.rpm import RPM
    from engine.models.sparseposer import SparsePoser
    from engine.models.vae import PoseVAE


def config_dict(cfg: Any) -> dict:
    out = dataclasses.asdict(cfg)
    return {k: list(v) if isinstance(v, tuple) else v for k, v in out.items()}


def start_from(model: PoseVAE | TemporalPredictor | SparsePoser | RPM, path: str, loader: Any) -> None:
    """Copy the weights of the file ``path`` (read by ``loader``, e.g. ``load_vae``) into
    ``model`` for fine-tuning; the two architectures (``config.to_dict()``) must match."""
    init, _ = loader(Path(path))
    if init.config.to_dict() != model.config.to_dict():
        raise UserError(
            f"init {path}: architecture {init.config.to_dict()} differs from the settings' {model.config.to_dict()}"
        )
    model.load_state_dict(init.state_dict())


def seed_everything(seed: int) -> None:
    random.seed(seed)
    np.random.seed(seed)
    torch.manual_seed(seed)


#: ``train --device`` choices: ``auto`` takes a CUDA device when torch sees one.
DEVICES = ("auto", "cpu", "cuda")


def pick_device(name: str = "auto", index: int = 0) -> torch.device:
    """The training device for ``--device name``; ``cuda`` without a CUDA device is a
    :class:`UserError` that says so."""
    if name not in DEVICES:
        raise UserError(f"--device must be one of {', '.join(DEVICES)}, got {name!r}")
    if name == "auto":
        name = "cuda" if torch.cuda.is_available() else "cpu"
    if name == "cuda":
        if not torch.cuda.is_available():
            raise UserError("--device cuda: torch sees no CUDA device here; use --device auto or cpu")
        return torch.device("cuda", index)
    return torch.device("cpu")


def on_device(batch: dict[str, torch.Tensor], device: torch.device) -> dict[str, torch.Tensor]:
    """``batch`` with every tensor on ``device`` (the data stays in CPU memory; only each
    step's batch moves)."""
    return {k: v.to(device, non_blocking=True) for k, v in batch.items()}


class Distributed:
    """Process-group facts; a single process when not launched by ``torchrun``.

    ``device`` is a :data:`DEVICES` name (each process takes the CUDA device of its local
    rank)."""

    def __init__(self, device: str = "auto") -> None:
        self.world = int(os.environ.get("WORLD_SIZE", "1"))
        self.rank = int(os.environ.get("RANK", "0"))
        self.local_rank = int(os.environ.get("LOCAL_RANK", "0"))
        self.device = pick_device(device, self.local_rank)
        if self.device.type == "cuda":
            torch.cuda.set_device(self.device)
        if self.world > 1 and not dist.is_initialized():
            dist.init_process_group("nccl" if self.device.type == "cuda" else "gloo")
        if self.device.type == "cpu":
            # share the cores between processes; never raise an explicit OMP_NUM_THREADS
            cores = os.cpu_count() or 1
            torch.set_num_threads(min(torch.get_num_threads(), max(1, cores // self.world)))

    @property
    def main(self) -> bool:
        return self.rank == 0

    def own_stream(self, shared: torch.Generator, seed: int) -> torch.Generator:
        """The random stream of this rank's augmentation and noise.

        Every rank draws the same permutation from ``shared`` (so together they cover the
        epoch once); what each then draws for its own poses must differ, or the two halves
        of a step would take the same donor limbs, bone scales and latent noise. Rank 0
        keeps ``shared`` (a single process draws exactly what it always drew); another
        rank gets a generator of its own, seeded from ``seed`` and its rank, and reseeds the
        global stream (the encoder's sampling noise) the same way."""
        if self.rank == 0:
            return shared
        own = seed * 7919 + self.rank
        torch.manual_seed(own)
        return torch.Generator().manual_seed(own)

    def barrier(self) -> None:
        if self.world > 1:
            dist.barrier()

    def mean(self, value: float) -> float:
        if self.world == 1:
            return value
        t = torch.tensor([value], dtype=torch.float64)
        dist.all_reduce(t)
        return float(t.item()) / self.world

    def close(self) -> None:
        if self.world > 1 and dist.is_initialized():
            dist.destroy_process_group()


def save_checkpoint(path: Path, payload: dict) -> None:
    """``torch.save`` atomically."""
    with atomic_path(path, suffix=".pt") as tmp:
        torch.save(payload, tmp)


class CurveLog:
    """Per-epoch losses written as CSV and a PNG plot beside the checkpoints."""

    def __init__(self, out_dir: Path, rows: list[dict] | None = None):
        self.out_dir = Path(out_dir)
        self.rows: list[dict] = list(rows or [])

    def append(self, row: dict) -> None:
        self.rows.append(row)
        self.write()

    def write(self) -> None:
        if not self.rows:
            return
        keys = list(dict.fromkeys(k for r in self.rows for k in r))
        buf = io.StringIO()
        w = csv.DictWriter(buf, fieldnames=keys)
        w.writeheader()
        w.writerows(self.rows)
        write_bytes(self.out_dir / "losses.csv", buf.getvalue().encode())
        self._plot(keys)

    def _plot(self, keys: list[str]) -> None:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt

        series = [k for k in keys if k not in ("epoch", "step", "minutes")]
        fig, ax = plt.subplots(figsize=(8, 4.5))
        epochs = [r.get("epoch", i) for i, r in enumerate(self.rows)]
        for k in series:
            vals = [r.get(k) for r in self.rows]
            if all(v is not None and v > 0 for v in vals):
                ax.plot(epochs, [float(v) for v in vals if v is not None], label=k)
        ax.set_yscale("log")
        ax.set_xlabel("epoch")
        ax.set_ylabel("loss / error")
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=7)
        fig.tight_layout()
        with atomic_path(self.out_dir / "losses.png", suffix=".png") as tmp:
            fig.savefig(tmp, dpi=90)
        plt.close(fig)
