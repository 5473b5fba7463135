"""Load ``data prepare`` output into in-memory tensors for training.

Features are computed once at load time (vectorised), so a training step is only
indexing: the corpus (~100 k frames) fits in memory comfortably.
"""

from __future__ import annotations

import json
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import torch

from engine.errors import UserError
from engine.kinematics.features import heights_from_root_space, pose_from_motion, root_space_features


@dataclass
class PoseData:
    """Per-frame training tensors of one split (N frames from several clips).

    Attributes
    ----------
    dq : (N, 22, 8) raw encoder input.   rot : (N, 22, 4) target pose quaternions (w >= 0).
    disp : (N, 3) root displacement, m.  pos : (N, 22, 3) root-space joint positions, m.
    offsets : (N, 22, 3) bone offsets.   heights : (N, 6) heights of root, head, hands, feet.
    has_next : (N,) bool, frame i+1 belongs to the same clip.
    clip : (N,) int clip index.          local_rot (N, 22, 4) / root_pos (N, 3): the motion.
    """

    dq: torch.Tensor
    rot: torch.Tensor
    disp: torch.Tensor
    pos: torch.Tensor
    offsets: torch.Tensor
    heights: torch.Tensor
    has_next: torch.Tensor
    clip: torch.Tensor
    local_rot: torch.Tensor
    root_pos: torch.Tensor
    names: list[str]

    def __len__(self) -> int:
        return self.dq.shape[0]


def read_manifest(data_dir: Path) -> dict:
    path = Path(data_dir) / "manifest.json"
    if not path.is_file():
        raise UserError(f"{path} not found: run `dragposer-studio data prepare --out {data_dir}` first")
    try:
        return json.loads(path.read_text())
    except json.JSONDecodeError as exc:
        raise UserError(f"{path}: not valid JSON ({exc})") from exc


@dataclass(frozen=True)
class ShardMotion:
    """One prepared shard's motion: local rotations ``(F, 22, 4)``, root positions
    ``(F, 3)`` and joint positions ``(F, 22, 3)`` (metres, z up), at ``fps``."""

    local_rot: np.ndarray
    root_pos: np.ndarray
    positions: np.ndarray
    fps: float


def shard_motions(data_dir: Path, split: str, mirrored: bool = True) -> Iterator[ShardMotion]:
    """Every shard of ``split`` in a prepared folder (its mirrored copies unless
    ``mirrored`` is False) with its forward kinematics; a folder without prepared data, or
    without a shard of ``split``, is named (:class:`UserError`)."""
    from engine.kinematics.fk import fk_positions

    manifest = read_manifest(data_dir)
    fps, found = float(manifest["fps"]), False
    for e in manifest["files"]:
        if e["split"] != split or (e["mirrored"] and not mirrored):
            continue
        with np.load(Path(data_dir) / e["shard"]) as z:
            local, root, offsets = z["local_rot"], z["root_pos"], z["offsets"]
        found = True
        yield ShardMotion(local, root, fk_positions(local, root, offsets), fps)
    if not found:
        raise UserError(f"{Path(data_dir) / 'manifest.json'}: no {split} shards")


def load_split(data_dir: Path, split: str, max_clips: int | None = None) -> PoseData:
    """All shards of ``split`` ("train", "val" or "test") as one :class:`PoseData`."""
    data_dir = Path(data_dir)
    man = read_manifest(data_dir)
    entries = [e for e in man["files"] if e["split"] == split][:max_clips]
    if not entries:
        raise UserError(f"{data_dir}: no '{split}' shards in manifest.json")
    parts: dict[str, list] = {k: [] for k in PoseData.__dataclass_fields__ if k != "names"}
    for ci, e in enumerate(entries):
        npz = np.load(data_dir / e["shard"])
        lr = torch.from_numpy(npz["local_rot"]).double()
        rp = torch.from_numpy(npz["root_pos"]).double()
        off = torch.from_numpy(npz["offsets"]).double()
        rot, disp = pose_from_motion(lr, rp)
        pos, dq = root_space_features(rot, disp, off)  # one FK pass: a third of loading
        n = lr.shape[0]
        parts["dq"].append(dq)
        parts["rot"].append(rot)
        parts["disp"].append(disp)
        parts["pos"].append(pos)
        parts["offsets"].append(off.expand(n, -1, -1))
        parts["heights"].append(heights_from_root_space(lr[:, 0], rp, pos))
        nxt = torch.ones(n, dtype=torch.bool)
        nxt[-1] = False
        parts["has_next"].append(nxt)
        parts["clip"].append(torch.full((n,), ci, dtype=torch.long))
        parts["local_rot"].append(lr)
        parts["root_pos"].append(rp)
    cat = {k: torch.cat(v) for k, v in parts.items()}
    for k, v in cat.items():
        if v.is_floating_point():
            cat[k] = v.float()
    return PoseData(**cat, names=[e["source"] + (" (mirror)" if e["mirrored"] else "") for e in entries])
