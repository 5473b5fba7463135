"""The latent map: a fixed 2D projection of the pose VAE's latent space.

A principal-component projection fitted once on the shipped pose bank's latents (the
VAE encoder's means of the training poses, ``assets/models/pose_bank.npz``) and shipped
beside the models as ``assets/models/latent_map.npz``
(``scripts/build_latent_map.py`` makes it). It also holds what the readouts need from
the training distribution: a density grid of the bank's latents in the map plane, each
dimension's standard deviation (the dimension sweep's sigma) and the thresholds of the
flag rule (:mod:`engine.latent.readouts`).

Numpy only, so the studio's widgets may project points without torch.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from engine.errors import UserError
from engine.input_files import file_sha256

DEFAULT_MAP = Path(__file__).resolve().parents[2] / "assets" / "models" / "latent_map.npz"
#: Cells per side of the density grid.
GRID = 96
#: Quantiles of the bank's projected coordinates the map's extent spans (then widened by
#: :data:`MARGIN` of its size on each side), so a few outliers do not shrink the picture.
EXTENT_QUANTILES = (0.001, 0.999)
MARGIN = 0.15

_FIELDS = (
    "mean",
    "components",
    "explained",
    "sigma",
    "density",
    "extent",
    "nn_threshold",
    "norm_threshold",
    "vae_sha256",
)


@dataclass(frozen=True)
class LatentMap:
    """A fixed 2D projection of the latent space and the training distribution in it.

    Attributes
    ----------
    mean : ndarray (L,)
        Mean of the fitted latents.
    components : ndarray (2, L)
        Unit principal axes: map ``x`` and ``y``.
    explained : ndarray (2,)
        Fraction of the latents' total variance along each axis (0-1).
    sigma : ndarray (L,)
        Standard deviation of each latent dimension over the fitted latents.
    density : ndarray (GRID, GRID) float32
        Fitted latents per cell of the map plane, rows ``y`` (bottom first), columns ``x``.
    extent : ndarray (4,)
        ``x0, x1, y0, y1`` of the density grid in map units.
    nn_threshold : float
        Distance to the nearest bank latent above which a frame is flagged.
    norm_threshold : float
        Latent norm above which a frame is flagged.
    vae_sha256 : str
        Hash of the VAE weights file whose latents were fitted ("" = unknown).
    """

    mean: np.ndarray
    components: np.ndarray
    explained: np.ndarray
    sigma: np.ndarray
    density: np.ndarray
    extent: np.ndarray
    nn_threshold: float = float("inf")
    norm_threshold: float = float("inf")
    vae_sha256: str = ""

    @property
    def latent_dim(self) -> int:
        return int(self.mean.shape[0])

    def project(self, z: np.ndarray) -> np.ndarray:
        """Map coordinates ``(..., 2)`` of latents ``z (..., L)``."""
        z = np.asarray(z, dtype=np.float64)
        if z.shape[-1] != self.latent_dim:
            raise ValueError(f"latent of size {z.shape[-1]}, the map is of size {self.latent_dim}")
        return (z - self.mean) @ self.components.T

    def project_direction(self, v: np.ndarray) -> np.ndarray:
        """Map-plane components ``(..., 2)`` of latent-space vectors ``v (..., L)`` (no
        centring: a direction, e.g. a gradient)."""
        return np.asarray(v, dtype=np.float64) @ self.components.T

    def lift(self, xy: np.ndarray) -> np.ndarray:
        """The latent ``(..., L)`` of map point ``xy (..., 2)``: the mean plus the point
        along the two axes (zero along every other principal direction)."""
        return self.mean + np.asarray(xy, dtype=np.float64) @ self.components

    def move_to(self, latent: np.ndarray, xy: np.ndarray) -> np.ndarray:
        """``latent (L,)`` moved within the map plane so that it projects to ``xy (2,)``,
        its components along the other principal directions kept: a point near a frame's
        own marker decodes to a pose near that frame's (the studio's hover and click)."""
        z = np.asarray(latent, dtype=np.float64).ravel()
        return z + (np.asarray(xy, dtype=np.float64).reshape(2) - self.project(z)) @ self.components

    def save(self, path: str | Path) -> None:
        """Write the map as a compressed ``.npz`` of plain arrays, atomically."""
        from engine.atomic import atomic_path

        with atomic_path(path, suffix=".npz") as tmp:
            np.savez_compressed(
                tmp,
                mean=self.mean,
                components=self.components,
                explained=self.explained,
                sigma=self.sigma,
                density=self.density.astype(np.float32),
                extent=self.extent,
                nn_threshold=np.array(self.nn_threshold),
                norm_threshold=np.array(self.norm_threshold),
                vae_sha256=np.array(self.vae_sha256),
            )

    @classmethod
    def load(cls, path: str | Path) -> "LatentMap":
        """Read a map written by :meth:`save` (plain arrays only, no pickles).

        Raises
        ------
        UserError
            When the file is missing, is not an ``.npz`` or lacks a field (named).
        """
        try:
            with np.load(Path(path), allow_pickle=False) as d:
                missing = [f for f in _FIELDS if f not in d.files]
                if missing:
                    raise UserError(f"{path}: not a latent map (no field {missing[0]!r})")
                m = cls(
                    d["mean"].astype(np.float64),
                    d["components"].astype(np.float64),
                    d["explained"].astype(np.float64),
                    d["sigma"].astype(np.float64),
                    d["density"].astype(np.float32),
                    d["extent"].astype(np.float64),
                    float(d["nn_threshold"]),
                    float(d["norm_threshold"]),
                    str(d["vae_sha256"]),
                )
        except (OSError, ValueError) as exc:
            raise UserError(f"{path}: not a latent map ({exc})") from None
        L = m.mean.shape[0]
        for name, shape in (("components", (2, L)), ("sigma", (L,)), ("explained", (2,)), ("extent", (4,))):
            if getattr(m, name).shape != shape:
                raise UserError(f"{path}: field {name!r} has shape {getattr(m, name).shape}, expected {shape}")
        return m


def fit_map(latents: np.ndarray, grid: int = GRID, vae_sha256: str = "") -> LatentMap:
    """Fit the projection and the density grid on ``latents (N, L)``.

    The axes are the two leading eigenvectors of the latents' covariance, each signed so
    that its largest-magnitude entry is positive (the same file comes out of the same
    latents on any machine). Thresholds are left infinite (:func:`with_thresholds`).
    """
    z = np.asarray(latents, dtype=np.float64)
    if z.ndim != 2 or len(z) < 3:
        raise ValueError(f"need latents (N, L) with N >= 3, got shape {z.shape}")
    mean = z.mean(0)
    cov = np.cov(z - mean, rowvar=False)
    w, v = np.linalg.eigh(cov)
    order = np.argsort(w)[::-1][:2]
    comps = v[:, order].T.copy()
    for i in range(2):
        if comps[i, np.argmax(np.abs(comps[i]))] < 0:
            comps[i] = -comps[i]
    explained = w[order] / w.sum()
    xy = (z - mean) @ comps.T
    lo, hi = np.quantile(xy, EXTENT_QUANTILES, axis=0)
    pad = MARGIN * (hi - lo)
    extent = np.array([lo[0] - pad[0], hi[0] + pad[0], lo[1] - pad[1], hi[1] + pad[1]])
    density, _, _ = np.histogram2d(xy[:, 1], xy[:, 0], bins=grid, range=[extent[2:], extent[:2]])
    return LatentMap(mean, comps, explained, z.std(0), density.astype(np.float32), extent, vae_sha256=vae_sha256)


def with_thresholds(m: LatentMap, nn_threshold: float, norm_threshold: float) -> LatentMap:
    """``m`` with the flag rule's thresholds set."""
    import dataclasses

    return dataclasses.replace(m, nn_threshold=float(nn_threshold), norm_threshold=float(norm_threshold))


@functools.cache
def default_map() -> LatentMap | None:
    """The shipped map (loaded once per process), or None when it is missing or belongs
    to another VAE than the shipped one (its latents would mean other poses). Imports
    no torch, so the studio's widgets may call it."""
    vae = DEFAULT_MAP.with_name("vae.pt")  # engine.models.loading.DEFAULT_VAE, without importing torch
    if not (DEFAULT_MAP.is_file() and vae.is_file()):
        return None
    m = LatentMap.load(DEFAULT_MAP)
    if m.vae_sha256 and m.vae_sha256 != file_sha256(vae):
        return None
    return m
