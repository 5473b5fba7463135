"""The optimizer plots' log y axes: tick labels that never overlap and say the value
where they are drawn (pyqtgraph's own axis stacked "0.003".."0.05" in a short plot)."""

from __future__ import annotations

import math

import pytest
from PyQt6.QtGui import QFontMetricsF, QPainter, QPicture

from tests.widgets.conftest import shown
from widgets.log_axis import label, labels
from widgets.plots import LossPlots

_POWER = str.maketrans("⁰¹²³⁴⁵⁶⁷⁸⁹⁻", "0123456789-")


def value_of(text: str) -> float:
    """The number a tick label shows: "0.003", "10⁻⁶", "2·10⁻⁶"."""
    if "10" in text and text.translate(_POWER) != text:
        mantissa, _, power = text.rpartition("10")
        return float(mantissa.rstrip("·") or 1) * 10.0 ** int(power.translate(_POWER))
    return float(text)


def drawn_labels(plot):
    """``(log10 value at the label's centre, text, centre y px)`` of every y tick label,
    the label line height (px) and the number of tick marks, from the draw specs the
    axis paints (set up as ``AxisItem.paint`` does)."""
    axis, view = plot.getAxis("left"), plot.getViewBox()
    picture = QPicture()
    painter = QPainter(picture)
    try:
        if axis.style["tickFont"] is not None:
            painter.setFont(axis.style["tickFont"])
        height = QFontMetricsF(painter.font()).height()
        _, ticks, texts = axis.generateDrawSpecs(painter)
    finally:
        painter.end()
    out = []
    for rect, _, text in texts:
        centre = axis.mapToScene(rect.center())
        out.append((view.mapSceneToView(centre).y(), text, centre.y()))
    return sorted(out, key=lambda t: t[2]), height, len(ticks)


@pytest.fixture
def plots(qtbot):
    """The three plots at about the size they have in the window (1600x980)."""
    return shown(qtbot, LossPlots(), 640, 250)


def _losses(n: int = 11) -> tuple[dict, ...]:
    """A frame like the screenshot's: total ~0.04, prior ~0.02, trackers ~0.003-0.006."""
    return tuple(
        {
            "total": 0.045 - 0.0015 * i,
            "temporal_prior": 0.022 - 0.0006 * i,
            "sensor:upperneck": 0.006 - 0.0001 * i,
            "sensor:lwrist": 0.0035,
        }
        for i in range(n)
    )


def assert_readable(plot, at_least: int) -> list[str]:
    shown, height, ticks = drawn_labels(plot)
    texts = [t for _, t, _ in shown]
    assert len(shown) >= at_least, texts
    for (_, a, ya), (_, b, yb) in zip(shown, shown[1:]):
        assert yb - ya >= height, f"labels {a!r} and {b!r} overlap: {yb - ya:.1f} px apart, {height:.1f} px high"
    for y, text, _ in shown:  # each label says the value where it is drawn
        assert abs(math.log10(value_of(text)) - y) < 0.02, (text, 10**y)
    assert ticks >= len(shown)
    return texts


def test_a_frames_losses_of_a_decade_or_two_get_readable_labels(plots, fake_snapshot):
    """The screenshot's case, fed as the window feeds it."""
    plots.update_snapshot(fake_snapshot(seq=1, losses=_losses()))
    plot = plots.iteration_plot
    lo, hi = plot.getViewBox().viewRange()[1]
    assert 10**lo < 0.0036 and 10**hi > 0.04  # spans ~1.2 decades
    texts = assert_readable(plot, at_least=2)
    assert "0.01" in texts
    shown, _, ticks = drawn_labels(plot)
    assert ticks > len(shown), "the unlabelled multiples keep their tick marks"


@pytest.mark.parametrize(
    "lo, hi, at_least",
    [
        (0.003, 0.05, 2),  # a decade or two: pyqtgraph labelled every multiple here
        (0.002, 0.5, 2),
        (1e-6, 0.1, 3),  # many decades: a readable subset of them
        (1e-12, 10.0, 3),
        (5.0, 2000.0, 2),  # milliseconds per frame
        (0.02, 0.05, 2),  # inside one decade
        (0.0231, 0.0235, 1),  # a nearly flat loss: evenly spaced values
    ],
)
@pytest.mark.parametrize("which", ["iteration_plot", "cost_plot", "history_plot"])
def test_every_log_plot_labels_any_range_without_overlap(plots, qtbot, which, lo, hi, at_least):
    plot = getattr(plots, which)
    plot.setYRange(math.log10(lo), math.log10(hi), padding=0)
    assert_readable(plot, at_least)


def test_labels_share_one_style_per_axis():
    assert labels([0.003, 0.01, 0.05]) == ["0.003", "0.01", "0.05"]
    assert labels([20.0, 1000.0]) == ["20", "1000"]
    assert labels([1e-6, 1e-4, 0.01]) == ["10⁻⁶", "10⁻⁴", "10⁻²"]  # not "0.01" beside "10⁻⁶"
    assert label(2e-6, plain=False) == "2·10⁻⁶" and value_of("2·10⁻⁶") == pytest.approx(2e-6)
