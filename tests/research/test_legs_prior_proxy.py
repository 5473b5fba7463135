"""research/legs_prior_proxy.py: its brute-force prior lookup gives the pose bank's own
answer, and the bank's rows are chained back within a clip only."""

from __future__ import annotations

import numpy as np
import torch

from engine.solver.tracker_prior import ANCHORS, BANK_JOINTS, LAG, PoseBank
from tests.engine.test_tracker_prior import _random_readings

from .script_loader import load_script

JOINTS = ("root", "upperneck", "lwrist", "rwrist")


def _clip_bank(rng, clips=(30, 20, 25)) -> PoseBank:
    """Clips of consecutive rows whose ``prev_anchor`` is the previous row's anchor (a
    clip's first row: its own), as the shipped bank's rows are."""
    pos, rot = _random_readings(rng, sum(clips), len(BANK_JOINTS))
    anchors = [BANK_JOINTS.index(a) for a in ANCHORS]
    prev = pos[:, anchors].copy()
    start = 0
    for n in clips:
        prev[start + 1 : start + n] = pos[start : start + n - 1][:, anchors]
        start += n
    return PoseBank(pos, rot, prev, rng.normal(size=(len(pos), 24)).astype(np.float32), "abc", 4)


def test_rows_are_chained_back_within_their_clip_only():
    lp = load_script("legs_prior_proxy")
    bank = _clip_bank(np.random.default_rng(0))
    back = lp._clip_rows_back(bank, 2)
    assert back.tolist()[:4] == [0, 0, 0, 1] and back[30] == 30 and back[31] == 30 and back[33] == 31
    assert back[50] == 50 and back[74] == 72


def test_the_brute_force_lookup_is_the_pose_bank_s_lookup():
    lp = load_script("legs_prior_proxy")
    rng = np.random.default_rng(1)
    bank = _clip_bank(rng)
    cols = [BANK_JOINTS.index(j) for j in JOINTS]
    pos, rot = _random_readings(rng, 12, len(BANK_JOINTS))
    w = np.clip(np.arange(12)[:, None] + np.arange(-LAG, 1)[None], 0, None)
    p, r = pos[:, cols][w], rot[:, cols][w]
    want = bank.latent_frames(JOINTS, p, r, k=4)
    got = lp.Variant(bank).latents(p, r, 4)
    torch.testing.assert_close(got, want)
    # weighting a block of columns changes the neighbours
    weights = np.ones(lp.Variant(bank).table.shape[1])
    weights[9] = 50.0  # the anchor's height
    assert not torch.allclose(lp.Variant(bank, weights=weights).latents(p, r, 4), want)


def test_the_gap_shares_sum_to_the_difference_and_the_oracles_touch_only_the_legs():
    lp = load_script("legs_prior_proxy")
    rng = np.random.default_rng(2)
    dp, ik = rng.uniform(0, 10, (40, 22)), rng.uniform(0, 10, (40, 22))
    shares = lp.gap_shares(dp, ik)
    assert abs(sum(shares.values()) - (dp.mean() - ik.mean())) < 1e-9
    assert shares["lelbow"] == (dp[:, 16] - ik[:, 16]).mean() / 22
    speed = np.r_[np.zeros(10), np.ones(30)]  # the first 10 frames standing
    o = lp.leg_oracles(dp, ik, speed)
    still = dp.copy()
    still[:10, lp.LEGS] = ik[:10, lp.LEGS]
    assert o["standing"] == still.mean() and o["as_measured"] == dp.mean() and o["ik"] == ik.mean()
    assert o["best_legs"] < o["as_measured"]
    best = dp.copy()
    best[:, lp.LEGS] = np.minimum(dp[:, lp.LEGS], ik[:, lp.LEGS])
    assert o["best_legs"] == best.mean()
