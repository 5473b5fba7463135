"""The latent map: the PCA fit, its file, and the shipped map."""

from __future__ import annotations

import numpy as np
import pytest

from engine.errors import UserError
from engine.latent.projection import GRID, LatentMap, default_map, fit_map, with_thresholds
from engine.latent.readouts import bank_latents


def _cloud(n: int = 4000, seed: int = 0) -> tuple[np.ndarray, np.ndarray]:
    """Latents (n, 6) spread 3 and 2 along two known orthonormal axes, 0.1 elsewhere."""
    rng = np.random.default_rng(seed)
    q, _ = np.linalg.qr(rng.normal(size=(6, 6)))
    scales = np.array([3.0, 2.0, 0.1, 0.1, 0.1, 0.1])
    z = (rng.normal(size=(n, 6)) * scales) @ q.T + 0.5
    return z, q


def test_fit_finds_the_principal_axes_and_their_variance():
    z, q = _cloud()
    m = fit_map(z)
    assert abs(abs(m.components[0] @ q[:, 0]) - 1) < 1e-3
    assert abs(abs(m.components[1] @ q[:, 1]) - 1) < 1e-3
    total = 9 + 4 + 4 * 0.01
    assert m.explained == pytest.approx([9 / total, 4 / total], abs=0.02)
    assert m.mean == pytest.approx(np.full(6, 0.5), abs=0.1)
    assert m.sigma.shape == (6,) and m.density.shape == (GRID, GRID)
    # nearly all points fall inside the grid (the extent spans 99.8 % plus a margin)
    assert m.density.sum() > 0.995 * len(z)


def test_project_and_lift_are_inverse_in_the_plane():
    z, _ = _cloud()
    m = fit_map(z)
    xy = np.array([[1.0, -2.0], [0.3, 0.4]])
    assert m.project(m.lift(xy)) == pytest.approx(xy)
    assert m.project(m.mean) == pytest.approx([0.0, 0.0])
    z0 = z[10]
    moved = m.move_to(z0, [0.5, 0.25])
    assert m.project(moved) == pytest.approx([0.5, 0.25])
    # only the plane's components changed
    assert (moved - z0) - ((moved - z0) @ m.components.T) @ m.components == pytest.approx(np.zeros(6), abs=1e-9)
    with pytest.raises(ValueError, match="size 5"):
        m.project(np.zeros(5))


def test_density_rows_are_y_and_columns_x():
    z, _ = _cloud()
    m = fit_map(z)
    xy = m.project(z)
    inside = (
        (xy[:, 0] >= m.extent[0]) & (xy[:, 0] <= m.extent[1]) & (xy[:, 1] >= m.extent[2]) & (xy[:, 1] <= m.extent[3])
    )
    cols, _ = np.histogram(xy[inside, 0], bins=GRID, range=m.extent[:2])
    rows, _ = np.histogram(xy[inside, 1], bins=GRID, range=m.extent[2:])
    assert m.density.sum(0) == pytest.approx(cols)
    assert m.density.sum(1) == pytest.approx(rows)


def test_save_and_load_round_trip(tmp_path):
    z, _ = _cloud()
    m = with_thresholds(fit_map(z, vae_sha256="abc"), 1.5, 4.0)
    m.save(tmp_path / "map.npz")
    back = LatentMap.load(tmp_path / "map.npz")
    assert back.components == pytest.approx(m.components)
    assert back.density == pytest.approx(m.density)
    assert (back.nn_threshold, back.norm_threshold, back.vae_sha256) == (1.5, 4.0, "abc")


def test_load_names_the_missing_field(tmp_path):
    np.savez(tmp_path / "bad.npz", mean=np.zeros(3))
    with pytest.raises(UserError, match="bad.npz.*'components'"):
        LatentMap.load(tmp_path / "bad.npz")
    (tmp_path / "text.npz").write_text("not a zip")
    with pytest.raises(UserError, match="text.npz: not a latent map"):
        LatentMap.load(tmp_path / "text.npz")


def test_shipped_map_is_the_fit_of_the_shipped_bank():
    m = default_map()
    assert m is not None, "assets/models/latent_map.npz missing or made for another VAE"
    refit = fit_map(bank_latents())
    assert m.components == pytest.approx(refit.components, abs=1e-6)
    assert m.density == pytest.approx(refit.density)
    # the figure the model card states
    assert m.explained.sum() == pytest.approx(0.354, abs=0.001)
    assert 0 < m.nn_threshold < 10 and 0 < m.norm_threshold < 20
