"""research/ceiling_coverage.py: frames fall into the coverage bins by distance, each bin's
ceiling is the mean of its frames, and HDM05 file names give their motion class."""

from __future__ import annotations

import numpy as np
import pytest

from .script_loader import load_script


def test_frames_are_binned_by_their_coverage_distance():
    cc = load_script("ceiling_coverage")
    rows = [{"err_cm": [1.0, 3.0, 10.0], "cover_cm": [1.0, 2.0, 20.0]}, {"err_cm": [5.0], "cover_cm": [7.0]}]
    bins = cc.binned(rows)
    assert len(bins) == len(cc.BINS) - 1
    share, mean, n = zip(*bins)
    assert sum(n) == 4 and sum(share) == pytest.approx(100.0)
    assert bins[0] == (50.0, 2.0, 2)  # under 3 cm: the frames at 1 and 2 cm
    assert bins[3][1:] == (5.0, 1)  # 6-8 cm
    assert bins[-1][1:] == (10.0, 1)  # over 15 cm
    assert np.isnan(bins[1][1])  # an empty bin has no mean


@pytest.mark.parametrize(
    "name, motion",
    [
        ("HDM_bd_depositFloorR_001_120.amc", "depositFloorR"),
        ("HDM_tr_elbowToKnee1RepsLelbowStart_002_120.amc", "elbowToKnee1RepsLelbowStart"),
        ("other.bvh", "other"),
    ],
)
def test_hdm05_names_give_their_motion_class(name, motion):
    assert load_script("ceiling_coverage").hdm05_class(f"/data/hdm05/{name}") == motion
