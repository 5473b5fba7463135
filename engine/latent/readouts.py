"""Prior readouts: how far a frame's latent sits from what the VAE was trained on.

Per frame, three distances in latent units:

* ``nearest``: Euclidean distance to the nearest pose-bank latent (the encoder's means of
  every 4th training frame, ``assets/models/pose_bank.npz``): near 0 inside the training
  data, large where the optimizer pushed the latent off it;
* ``norm``: the latent's Euclidean norm. The VAE's prior is N(0, I), under which the norm
  of a 24-D latent is about 4.9; the trained encoder's latents are tighter (median 3.05 over
  the bank), so a norm far above the bank's is an unlikely latent under either;
* ``predictor``: distance from the frame's prior latent (the temporal predictor's, or the
  pose bank's when the tracker prior answers) to the solution: how far the trackers and
  constraints had to pull the latent.

**Flag rule**: a frame is flagged when ``nearest > nn_threshold`` or ``norm >
norm_threshold`` (both stored in the latent map; ``scripts/build_latent_map.py`` sets them
from unseen poses, see ``assets/models/README.md``, "Latent map").

Numpy only.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from engine.errors import UserError
from engine.latent.projection import LatentMap

#: Query rows per distance block: the block's (rows, N) float32 distances stay ~25 MB.
BLOCK = 64
DEFAULT_BANK = Path(__file__).resolve().parents[2] / "assets" / "models" / "pose_bank.npz"


class NearestLatents:
    """Exact nearest-neighbour search among reference latents ``(N, L)`` (brute force,
    blocked; about 0.4 ms per query on the shared machine for the shipped 96 072 latents).

    Parameters
    ----------
    latents : ndarray (N, L)
    """

    def __init__(self, latents: np.ndarray) -> None:
        self.latents = np.ascontiguousarray(latents, dtype=np.float32)
        if self.latents.ndim != 2 or len(self.latents) == 0:
            raise ValueError(f"need reference latents (N, L) with N > 0, got shape {self.latents.shape}")
        self._sq = np.einsum("ij,ij->i", self.latents, self.latents)

    def query(self, z: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Distance ``(F,)`` to the nearest reference latent and its row ``(F,)`` int, for
        latents ``z (F, L)`` (or ``(L,)``, giving 0-d arrays)."""
        q = np.asarray(z, dtype=np.float32)
        single = q.ndim == 1
        q = q.reshape(-1, self.latents.shape[1])
        dist, idx = np.empty(len(q)), np.empty(len(q), dtype=np.int64)
        for s in range(0, len(q), BLOCK):
            b = q[s : s + BLOCK]
            d2 = self._sq[None, :] - 2.0 * (b @ self.latents.T)  # + |b|^2, added after the argmin
            i = np.argmin(d2, axis=1)
            # the expansion loses digits near 0: the chosen row's distance is recomputed exactly
            dist[s : s + len(b)] = np.linalg.norm(self.latents[i].astype(np.float64) - b, axis=1)
            idx[s : s + len(b)] = i
        return (dist[0], idx[0]) if single else (dist, idx)


def bank_latents(path: str | Path = DEFAULT_BANK) -> np.ndarray:
    """The pose bank's latents ``(N, L)`` float32 (only that array is read).

    Raises
    ------
    UserError
        When the file is missing or holds no ``latents``.
    """
    try:
        with np.load(Path(path), allow_pickle=False) as d:
            return d["latents"].astype(np.float32)
    except (OSError, KeyError, ValueError) as exc:
        raise UserError(f"{path}: cannot read the pose bank's latents ({exc})") from None


@dataclass(frozen=True)
class Readouts:
    """Prior readouts of ``F`` frames (module doc).

    Attributes
    ----------
    nearest : ndarray (F,)
        Distance to the nearest bank latent.
    nearest_index : ndarray (F,) int
        That bank latent's row.
    norm : ndarray (F,)
        Latent norm.
    predictor : ndarray (F,)
        Distance from the frame's prior latent to the solution (NaN: none).
    flagged : ndarray (F,) bool
        The flag rule's verdict.
    """

    nearest: np.ndarray
    nearest_index: np.ndarray
    norm: np.ndarray
    predictor: np.ndarray
    flagged: np.ndarray

    def frame(self, i: int) -> dict[str, float]:
        """Frame ``i``'s readouts by name (``flagged`` as 0.0 / 1.0)."""
        return {
            "nearest": float(self.nearest[i]),
            "norm": float(self.norm[i]),
            "predictor": float(self.predictor[i]),
            "flagged": float(self.flagged[i]),
        }


def flag(m: LatentMap, nearest: np.ndarray, norm: np.ndarray) -> np.ndarray:
    """The flag rule: ``nearest > m.nn_threshold`` or ``norm > m.norm_threshold``."""
    return (np.asarray(nearest) > m.nn_threshold) | (np.asarray(norm) > m.norm_threshold)


def readouts(m: LatentMap, search: NearestLatents, latents: np.ndarray, priors: np.ndarray | None = None) -> Readouts:
    """Readouts of latents ``(F, L)`` with the frames' prior latents ``(F, L)`` (rows of
    NaN where a frame had none; None: no frame had one)."""
    z = np.asarray(latents, dtype=np.float64).reshape(-1, m.latent_dim)
    nearest, idx = search.query(z)
    norm = np.linalg.norm(z, axis=1)
    if priors is None:
        pred = np.full(len(z), np.nan)
    else:
        pred = np.linalg.norm(np.asarray(priors, dtype=np.float64).reshape(z.shape) - z, axis=1)
    return Readouts(nearest, idx, norm, pred, flag(m, nearest, norm))


def next_flagged(flagged: np.ndarray, frames: np.ndarray, after: int) -> int | None:
    """The first flagged frame after frame ``after`` (wrapping to the start), or None.

    Parameters
    ----------
    flagged : ndarray (F,) bool
    frames : ndarray (F,) int
        The frame index of each row.
    after : int
    """
    hits = np.asarray(frames)[np.asarray(flagged, bool)]
    if hits.size == 0:
        return None
    later = hits[hits > after]
    return int(later.min() if later.size else hits.min())
