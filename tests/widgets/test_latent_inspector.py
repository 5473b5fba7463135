"""The latent inspector's strip and bars: what pyqtgraph is handed, and readable labels.

An intermittent segfault in ``ImageItem.paint`` (seen five times under load while this
strip was painted, never reproduced) led to these invariants: the strip's image is a
private read-only copy that nothing writes after ``setImage``, with finite values and
finite levels, whatever the engine's latents hold.
"""

from __future__ import annotations

import warnings

import numpy as np
import pytest

from tests.widgets.conftest import FakeRecord, shown
from tests.widgets.test_log_axis import drawn_labels
from widgets.latent_inspector import LatentInspector, nice_ceil, strip_image


def _readonly(a: np.ndarray) -> np.ndarray:
    a = np.array(a, float)
    a.flags.writeable = False  # as engine.studio.snapshot.readonly hands them out
    return a


@pytest.fixture
def inspector(qtbot):
    """Shown at the size of the studio's latent dock (1600 x 980 window)."""
    return shown(qtbot, LatentInspector(), 430, 330)


def test_the_strip_gets_a_private_read_only_image_with_finite_levels(inspector, fake_snapshot):
    latents = [_readonly(np.linspace(-1, 1, 24) * k) for k in range(5)]
    latents[2] = _readonly(np.r_[np.nan, np.inf, -np.inf, np.ones(21)])  # a diverged solve
    recs = tuple(FakeRecord(k, 1, 1.0, {}, z) for k, z in enumerate(latents))
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        inspector.update_snapshot(fake_snapshot(seq=2, frame=4, latent=latents[-1], history=recs))
        inspector.repaint()
        inspector.grab()
    image = inspector.strip.image
    assert not image.flags.writeable and image.flags.c_contiguous
    assert not any(np.shares_memory(image, z) for z in latents)
    assert np.isfinite(image).all() and np.isfinite(inspector.strip.levels).all()
    assert inspector.strip.levels[1] == pytest.approx(4.0)  # the largest finite magnitude
    assert image[2, 0] == 0.0 and image[2, 1] == 4.0 and image[2, 2] == -4.0
    assert not [w for w in caught if issubclass(w.category, RuntimeWarning)], [str(w.message) for w in caught]


def test_an_image_handed_to_the_strip_is_never_written_afterwards(inspector, fake_snapshot, qtbot):
    """Shapes, NaNs, hidden and shown plots, resizes and repaints in quick succession."""
    rng = np.random.default_rng(3)
    handed: list[tuple[np.ndarray, np.ndarray]] = []
    for seq in range(2, 40):
        n = int(rng.choice([1, 2, 3, 30, 299, 300, 301]))
        lat = rng.normal(size=(n, 24)) * rng.choice([1e-9, 1.0, 1e6])
        if seq % 5 == 0:
            lat[rng.integers(n), rng.integers(24)] = np.nan
        latent = None if seq % 7 == 0 else lat[-1]  # a method without a latent hides the plots
        recs = tuple(FakeRecord(3 * k, 1, 1.0, {}, _readonly(z)) for k, z in enumerate(lat))
        inspector.update_snapshot(fake_snapshot(seq=seq, frame=3 * (n - 1), latent=latent, history=recs))
        if latent is not None:
            handed.append((inspector.strip.image, inspector.strip.image.copy()))
        if seq % 4 == 0:
            inspector.resize(int(rng.integers(200, 700)), int(rng.integers(200, 600)))
        inspector.repaint()
        qtbot.wait(1)
    assert len(handed) > 25
    for image, copy in handed:
        assert not image.flags.writeable
        np.testing.assert_array_equal(image, copy)


def test_strip_image_copies_even_a_contiguous_float_history():
    rows = np.arange(48, dtype=float).reshape(2, 24)
    image, lim = strip_image(list(rows))
    assert not np.shares_memory(image, rows) and lim == 47.0
    image, lim = strip_image([np.full(24, np.nan)])
    assert (image == 0).all() and lim > 0


@pytest.mark.parametrize(
    "x, m", [(0.0, 1e-6), (0.3, 0.5), (0.5, 0.5), (0.51, 1.0), (1.0, 1.0), (1.7, 2.0), (3.0, 5.0), (12.0, 20.0)]
)
def test_nice_ceil(x, m):
    assert nice_ceil(x) == pytest.approx(m)


@pytest.mark.parametrize("latent", [np.linspace(-1.0, 0.5, 24), np.linspace(-0.2, 0.2, 24), np.linspace(-3, 2.5, 24)])
def test_the_bars_y_labels_do_not_touch_at_the_studios_size(inspector, fake_snapshot, latent):
    """Seen in the studio: 0.5 / 0 / -0.5 / -1.0 on about 45 px, each label on the next."""
    inspector.update_snapshot(fake_snapshot(seq=2, latent=latent))
    inspector.repaint()
    shown, height, _ = drawn_labels(inspector.bars_plot)
    m = float(shown[0][1])
    # all three drawn: pyqtgraph drops a label that would stick out of the axis
    assert [t for _, t, _ in shown] == [f"{m:g}", "0", f"{-m:g}"], shown
    for (_, a, ya), (_, b, yb) in zip(shown, shown[1:]):
        assert yb - ya >= height, f"labels {a!r} and {b!r} overlap: {yb - ya:.1f} px apart, {height:.1f} px high"
    for y, text, _ in shown:  # each label says the value where it is drawn
        assert float(text) == pytest.approx(y, abs=0.02 * abs(latent).max())
    assert m >= np.abs(latent).max()  # the tallest bar stays inside the labelled range
