"""Checkpoints can never run code: every torch.load is weights_only with an allow-list."""

from __future__ import annotations

import re
from pathlib import Path

import pytest
import torch

from engine.errors import ModelFileError
from engine.models.loading import load_checkpoint, load_vae

REPO = Path(__file__).resolve().parents[2]


class _Planted:
    """Unpickling this calls ``Path.touch(marker)``: proof that code ran."""

    def __init__(self, marker: Path):
        self.marker = marker

    def __reduce__(self):
        return (Path.touch, (self.marker,))


def plant(path: Path, marker: Path) -> None:
    """Write a checkpoint whose unpickling would create ``marker``."""
    payload = {"kind": "vae", "format_version": 1, "config": {}, "state_dict": {}, "epoch": 1, "evil": _Planted(marker)}
    torch.save(payload, path)


def test_a_planted_checkpoint_runs_no_code(tmp_path):
    marker = tmp_path / "pwned"
    plant(tmp_path / "last.pt", marker)
    with pytest.raises(ModelFileError) as err:
        load_checkpoint(tmp_path / "last.pt", "checkpoint")
    assert not marker.exists(), "unpickling ran code from the checkpoint"
    text = str(err.value)
    assert "refused" in text and "\n" not in text and "weights_only" not in text
    with pytest.raises(ModelFileError):
        load_vae(tmp_path / "last.pt")
    assert not marker.exists()


def test_no_module_loads_with_weights_only_false():
    offenders = []
    for path in (REPO / "engine").rglob("*.py"):
        text = path.read_text()
        if re.search(r"weights_only\s*=\s*False", text) or re.search(r"torch\.load\((?![^)]*weights_only=True)", text):
            offenders.append(str(path.relative_to(REPO)))
    assert offenders == []


def test_real_checkpoints_still_load(tmp_path):
    import numpy as np

    from engine.training.common import save_checkpoint

    payload = {
        "state_dict": {"w": torch.zeros(2)},
        "optimizer": {"param_groups": [{"lr": 0.1, "fused": None}]},
        "epoch": 3,
        "curve": [{"epoch": 1, "loss": np.float64(0.5)}],
        "rng": torch.get_rng_state(),
    }
    save_checkpoint(tmp_path / "last.pt", payload)
    back = load_checkpoint(tmp_path / "last.pt", "checkpoint")
    assert back["epoch"] == 3 and float(back["curve"][0]["loss"]) == 0.5
