"""Prior readouts: nearest training latent, norm, prior distance, the flag rule."""

from __future__ import annotations

import numpy as np
import pytest

from engine.latent.projection import fit_map, with_thresholds
from engine.latent.readouts import BLOCK, NearestLatents, flag, next_flagged, readouts


def test_nearest_matches_a_plain_search_across_blocks():
    rng = np.random.default_rng(1)
    ref = rng.normal(size=(500, 24)).astype(np.float32)
    q = rng.normal(size=(BLOCK * 2 + 5, 24))
    dist, idx = NearestLatents(ref).query(q)
    full = np.linalg.norm(q[:, None, :] - ref[None].astype(np.float64), axis=-1)
    assert idx.tolist() == full.argmin(1).tolist()
    assert dist == pytest.approx(full.min(1), abs=1e-5)
    d1, i1 = NearestLatents(ref).query(ref[7])
    assert int(i1) == 7 and float(d1) == pytest.approx(0.0, abs=1e-6)


def test_flag_rule_uses_both_thresholds():
    m = with_thresholds(fit_map(np.random.default_rng(0).normal(size=(50, 4))), 1.0, 3.0)
    got = flag(m, np.array([0.5, 1.5, 0.5, 1.0]), np.array([2.0, 2.0, 3.5, 3.0]))
    assert got.tolist() == [False, True, True, False]


def test_readouts_of_latents_and_priors():
    rng = np.random.default_rng(2)
    ref = rng.normal(size=(200, 4))
    m = with_thresholds(fit_map(ref), 0.5, 100.0)
    z = np.vstack([ref[3], ref[3] + [2.0, 0, 0, 0]])
    r = readouts(m, NearestLatents(ref), z, np.vstack([ref[3] + [0, 0.3, 0, 0], np.full(4, np.nan)]))
    assert r.nearest[0] == pytest.approx(0.0, abs=1e-6) and r.nearest_index[0] == 3
    assert r.norm == pytest.approx(np.linalg.norm(z, axis=1))
    assert r.predictor[0] == pytest.approx(0.3) and np.isnan(r.predictor[1])
    assert r.flagged.tolist() == [False, r.nearest[1] > 0.5]
    assert np.isnan(readouts(m, NearestLatents(ref), z).predictor).all()
    assert set(r.frame(0)) == {"nearest", "norm", "predictor", "flagged"}


def test_next_flagged_wraps_to_the_first():
    frames = np.arange(10, 20)
    flagged = np.zeros(10, bool)
    flagged[[2, 7]] = True  # frames 12 and 17
    assert next_flagged(flagged, frames, 10) == 12
    assert next_flagged(flagged, frames, 12) == 17
    assert next_flagged(flagged, frames, 17) == 12
    assert next_flagged(np.zeros(10, bool), frames, 0) is None
