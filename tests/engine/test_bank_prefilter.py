"""The pose bank's exact prefilter (engine/solver/bank_prefilter.py): its bound is below
every true distance, gathered rows keep their bits, and lookups through it find exactly
what the whole table finds, with or without the rows kept near a live query's last
queries."""

from __future__ import annotations

import numpy as np
import pytest
import torch

from engine.solver import bank_prefilter as bp
from engine.solver.tracker_history import TrackerHistory
from engine.solver.tracker_prior import default_bank, features
from engine.tracking import simulate


def _rows(rng, n: int = 3000, d: int = 55) -> torch.Tensor:
    # strongly correlated columns (a few factors and a little noise), as tracker features are
    x = rng.normal(size=(n, 10)) @ rng.normal(size=(10, d)) + rng.normal(scale=0.1, size=(n, d))
    return torch.from_numpy(x.astype(np.float32))


def test_the_bound_is_below_every_true_distance_and_close_for_near_rows():
    rng = np.random.default_rng(0)
    rows = _rows(rng)
    pre = bp.Prefilter(rows)
    x = rows.double().numpy()
    for _ in range(20):
        q = (x[rng.integers(len(x))] + rng.normal(scale=0.1, size=x.shape[1])).astype(np.float32)
        b, offset, margin = pre.bound(q)
        true = ((x - q.astype(np.float64)) ** 2).sum(1)
        assert (b.double().numpy() + offset - margin <= true).all()
        # not vacuous: the bound of the nearest rows is most of their distance
        near = np.argsort(true)[1:100]
        assert (b.double().numpy()[near] + offset).sum() > 0.9 * true[near].sum()


def test_the_bounds_of_many_queries_are_each_querys_bound_and_pick_its_candidates():
    rng = np.random.default_rng(4)
    rows = _rows(rng)
    pre = bp.Prefilter(rows)
    x = rows.double().numpy()
    qs = (x[rng.integers(len(x), size=9)] + rng.normal(scale=0.1, size=(9, x.shape[1]))).astype(np.float32)
    many = pre.bounds(qs)
    assert many.shape == (9, len(x)) and many.dtype == torch.float32
    for q, b in zip(qs, many):
        one, _, margin = pre.bound(q)
        np.testing.assert_allclose(b.numpy(), one.numpy(), rtol=0, atol=0.01 * margin)
        worst = float(np.quantile(one.numpy(), 0.01))
        assert torch.equal(pre.candidates(q, worst, b), pre.candidates(q, worst)) or (
            # a row at the threshold may fall either side of it: only such rows differ
            set(pre.candidates(q, worst, b).tolist()) ^ set(pre.candidates(q, worst).tolist())
            <= set(np.flatnonzero(np.abs(one.numpy() - worst - 2 * margin) < 0.01 * margin).tolist())
        )


@pytest.mark.parametrize("m", [1, 5, 16, 47, 333])
def test_gathered_rows_keep_the_bits_of_the_whole_tables_product(m):
    rng = np.random.default_rng(1)
    table = _rows(rng, n=4000)
    norms = (table * table).sum(1)
    q = torch.from_numpy(rng.normal(size=55).astype(np.float32))
    full = norms - 2.0 * (table @ q)
    rows = torch.from_numpy(np.sort(rng.choice(len(table), m, replace=False)))
    assert torch.equal(bp.distances(table, norms, q, rows), full[rows])


def test_a_lookup_with_any_hint_finds_the_whole_tables_neighbours_in_its_order():
    rng = np.random.default_rng(2)
    table = _rows(rng, n=5000)
    norms = (table * table).sum(1)
    pre = bp.Prefilter(table)
    pruned = 0
    for _ in range(30):
        q32 = (table[rng.integers(len(table))].numpy() + rng.normal(scale=0.1, size=55)).astype(np.float32)
        q = torch.from_numpy(q32)
        want = (norms - 2.0 * (table @ q)).topk(8, largest=False).indices
        for hint in (want.flip(0), torch.from_numpy(rng.choice(len(table), 8, replace=False)), None):
            assert torch.equal(bp.nearest(table, norms, q, q32, pre, hint, 8), want)
        b, _, margin = pre.bound(q32)
        worst = float((norms - 2.0 * (table @ q))[want].max())
        pruned += int((b > worst + 2.0 * margin).sum())
    assert pruned > 0.5 * 30 * len(table)  # the prefilter spares most rows


def test_the_candidates_are_every_row_the_bound_cannot_rule_out():
    rng = np.random.default_rng(3)
    table = _walk_table(rng)
    norms = (table * table).sum(1)
    pre = bp.Prefilter(table)
    x = table.double().numpy()
    searched = 0
    for _ in range(40):
        q32 = (x[rng.integers(len(x))] + rng.normal(scale=0.05, size=55)).astype(np.float32)
        d = (norms - 2.0 * (table @ torch.from_numpy(q32))).double().numpy()
        worst = float(np.sort(d)[7])
        q64 = q32.astype(np.float64)
        pq, qq = q64 @ pre.basis, float(q64 @ q64)
        uq = np.append(pq, np.sqrt(max(qq - float(pq @ pq), 0.0)))
        proj = x @ pre.basis
        u = np.column_stack((proj, np.sqrt(np.maximum((x * x).sum(1) - (proj * proj).sum(1), 0.0))))
        exact = ((u - uq) ** 2).sum(1) - qq  # each row's bound, float64
        got = set(pre.candidates(q32, worst).tolist())
        assert set(np.flatnonzero(exact <= worst).tolist()) <= got
        searched += len(got)
    assert searched < 0.25 * 40 * len(x)  # most rows are ruled out


def _walk_table(rng, n: int = 6000, step: float = 0.05) -> torch.Tensor:
    # consecutive rows close together, as consecutive frames of the bank's clips are
    walk = np.cumsum(rng.normal(scale=step, size=(n, 10)), axis=0) @ rng.normal(size=(10, 55))
    return torch.from_numpy((walk + rng.normal(scale=0.02, size=walk.shape)).astype(np.float32))


def test_a_neighbourhood_kept_between_queries_finds_the_whole_tables_neighbours():
    rng = np.random.default_rng(5)
    # rows ~0.25 apart, a tenth of the search radius, as the bank's frames are
    table = _walk_table(rng, step=0.01)
    norms = (table * table).sum(1)
    pre = bp.Prefilter(table)
    near, hint = bp.Neighbourhood(), None
    x = table.numpy()
    # a query gliding along the table's rows, as a live performer's features do, then a jump
    path = [x[1000 + i] + rng.normal(scale=0.01, size=55) for i in range(60)] + [x[5000]]
    for q in path:
        q32 = q.astype(np.float32)
        qt = torch.from_numpy(q32)
        want = (norms - 2.0 * (table @ qt)).topk(8, largest=False).indices
        hint = bp.nearest(table, norms, qt, q32, pre, hint, 8, near=near)
        assert torch.equal(hint, want)
    # not vacuous: most queries were answered from the kept rows, the jump read the table
    assert 1 < near.refreshed < len(path) // 2


def test_a_neighbourhoods_candidates_hold_every_row_the_bound_cannot_rule_out():
    rng = np.random.default_rng(6)
    table = _walk_table(rng, step=0.01)
    pre = bp.Prefilter(table)
    norms = (table * table).sum(1)
    near = bp.Neighbourhood()
    x = table.double().numpy()
    proj = x @ pre.basis
    u = np.column_stack((proj, np.sqrt(np.maximum((x * x).sum(1) - (proj * proj).sum(1), 0.0))))
    for i in range(40):
        q32 = (x[2000 + i] + rng.normal(scale=0.01, size=55)).astype(np.float32)
        d = (norms - 2.0 * (table @ torch.from_numpy(q32))).double().numpy()
        worst = float(np.sort(d)[7])
        q64 = q32.astype(np.float64)
        exact = ((u - pre.point(q64)) ** 2).sum(1) - float(q64 @ q64)  # each row's bound, float64
        got = set(near.candidates(pre, q32, worst).tolist())
        assert set(np.flatnonzero(exact <= worst).tolist()) <= got
    assert near.refreshed < 20


@pytest.fixture
def clip():
    from engine.cli.bench import DEFAULT_CLIP
    from engine.motion.retarget import load_motion

    return load_motion(DEFAULT_CLIP)


def test_real_bank_lookups_over_a_clip_are_those_of_the_whole_table(clip):
    bank = default_bank()
    if bank is None:
        pytest.skip("the shipped pose bank is not installed")
    looked = 0
    for preset in ("6", "4"):
        hist = TrackerHistory()
        tr = simulate(clip, preset)
        reads = {j: n.refreshed for j, n in bank._near.items()}
        for i in range(min(len(clip), 120)):
            fr = tr.frame(i)
            hist.push({j: (r.position, r.rotation) for j, r in fr.readings.items() if r.connected and r.dof == 6})
            joints, pos, rot = hist.arrays()
            idx = bank._index(joints)
            tab, a = idx.table, joints.index("root")
            x = features(pos[-1:], rot[-1:], a, pos[:1, a])[0]
            q = torch.zeros(tab.table.shape[1])
            x32 = ((x - tab.mean[idx.cols]) / tab.std[idx.cols]).astype(np.float32)
            q[torch.from_numpy(idx.cols)] = torch.from_numpy(x32)
            want = (idx.norms - 2.0 * (tab.table @ q)).topk(bank.k, largest=False).indices
            assert torch.equal(bank.latent(joints, pos, rot), bank._latents[want].mean(0))
            assert torch.equal(bank._hints[joints], want)
            looked += 1
        # most frames were answered from the rows kept near the last queries
        assert bank._near[joints].refreshed - reads.get(joints, 0) < min(len(clip), 120) / 2
    assert looked == 2 * min(len(clip), 120)
