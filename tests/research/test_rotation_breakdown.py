"""research/rotation_breakdown.py: the per-file convention columns."""

from __future__ import annotations

import numpy as np

from .script_loader import load_script


def _script():
    return load_script("rotation_breakdown")


def _about_x(deg: float) -> np.ndarray:
    return np.array([np.cos(np.radians(deg) / 2), np.sin(np.radians(deg) / 2), 0.0, 0.0])


def test_per_file_row_reports_error_and_both_angles_from_identity():
    rb = _script()
    frames = 4
    gt = np.tile(np.array([1.0, 0.0, 0.0, 0.0]), (frames, 22, 1))
    rec = gt.copy()
    gt[:, 10] = _about_x(80.0)  # truth: upper back 80 deg from identity (one rig's convention)
    rec[:, 10] = _about_x(-10.0)  # reconstruction: the other convention, slightly bent
    rec[:, 11] = -_about_x(30.0)  # the sign of a quaternion does not matter
    err = np.zeros((frames, 22))
    err[:, 10] = 90.0
    mean, cols = rb.per_file_row(gt, rec, err, [10, 11, 0])
    assert mean == np.float64(90.0 / 22)
    (e10, a10, b10), (e11, a11, b11), (e0, a0, b0) = cols
    assert (e10, e11, e0) == (90.0, 0.0, 0.0)
    np.testing.assert_allclose([a10, b10, a11, b11, a0, b0], [80.0, 10.0, 0.0, 30.0, 0.0, 0.0], atol=1e-9)
