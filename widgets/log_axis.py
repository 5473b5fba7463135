"""A log-scale plot axis whose tick labels never overlap.

pyqtgraph's own log axis (``AxisItem.logTickValues``, 0.14) keeps the linear tick levels
whose spacing is at least a decade and, when fewer than three are left, adds every
1..9 multiple of each decade as one more level. On a range of one or two decades no
decade-spaced level survives, so the multiples become the *first* level, and the first
level is always labelled, whatever room it has: "0.003", "0.004", ... "0.05" were drawn
on top of each other in a plot 60 pixels high.

:class:`LogAxis` labels the richest set of readable values whose labels fit, measured
with the axis's font, and leaves the other multiples as unlabelled ticks:

* every multiple, then 1-2-3-5, 1-2-5, 1-3, the decades, then every 2nd, 3rd, 5th,
  10th... decade, the first set with at least two labels in view that fits;
* when none fits, the decade in view; when there is none (a range inside one decade,
  such as 0.0231..0.0235), evenly spaced values as on a linear axis.

Labels read as plain numbers ("0.003", "20", "1000") when all lie in [1e-3, 1e4), as
powers of ten ("10⁻⁶", "2·10⁻⁶") otherwise, one style per axis.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np
import pyqtgraph as pg
from PyQt6.QtGui import QFont, QFontMetricsF

#: Multiples of a decade to label, richest first.
MANTISSA_SETS = ((1, 2, 3, 4, 5, 6, 7, 8, 9), (1, 2, 3, 5), (1, 2, 5), (1, 3), (1,))
#: Steps (in decades) between labelled decades on a long range.
DECADE_STEPS = (2, 3, 5, 10, 20, 50, 100)
#: Free space kept between two labels (pixels).
LABEL_GAP = 3.0
#: Unlabelled ticks closer than this (pixels) are left out.
MIN_TICK_GAP = 3.0
_SUPERSCRIPT = str.maketrans("0123456789-", "⁰¹²³⁴⁵⁶⁷⁸⁹⁻")


def label(value: float, plain: bool) -> str:
    """``value`` as a tick label: ``plain`` "0.003" or powers of ten "3·10⁻³"."""
    if plain:
        return f"{value:.6g}"
    exponent = math.floor(math.log10(value) + 1e-9)
    mantissa = float(f"{value / 10.0**exponent:.6g}")
    power = "10" + str(exponent).translate(_SUPERSCRIPT)
    return power if mantissa == 1 else f"{mantissa:g}·{power}"


def labels(values: Sequence[float]) -> list[str]:
    """Labels of ``values`` (linear, > 0), all in one style (see the module docstring)."""
    plain = all(1e-3 <= v < 1e4 for v in values)
    return [label(v, plain) for v in values]


class LogAxis(pg.AxisItem):
    """An :class:`pyqtgraph.AxisItem` for log mode with labels chosen to fit.

    Tick level 0 is the labelled values, level 1 the unlabelled multiples of each
    decade (ticks only: ``maxTextLevel`` is 0). On a linear axis it behaves as the base
    class.
    """

    def __init__(self, orientation: str, **kwargs) -> None:
        super().__init__(orientation, **kwargs)
        self.setStyle(maxTextLevel=0)

    def tick_font(self) -> QFont:
        """The font tick labels are drawn with (the application's unless set)."""
        return self.style["tickFont"] or QFont()

    def logTickValues(self, minVal: float, maxVal: float, size: float, stdTicks: list) -> list:
        """Labelled and unlabelled ticks of the range ``minVal..maxVal`` (log10 units)
        on an axis ``size`` pixels long; see the module docstring."""
        lo, hi = sorted((minVal, maxVal))
        if not (math.isfinite(lo) and math.isfinite(hi)) or hi - lo <= 0 or size <= 0:
            return []
        px_per_decade = size / (hi - lo)
        shown = self._labelled(lo, hi, px_per_decade)
        if shown is None:  # inside one decade's step: evenly spaced values
            shown = self._linear(lo, hi, size)
        # unlabelled ticks: the richest set of multiples that is not a solid comb
        subs = next((s for s in MANTISSA_SETS if _min_gap(s) * px_per_decade >= MIN_TICK_GAP), (1,))
        minor = [v for v in _multiples(lo, hi, subs) if not _near(v, shown)]
        return [(None, shown), (None, minor)]

    def logTickStrings(self, values: list[float], scale: float, spacing: float) -> list[str]:
        return labels([10.0**v * scale for v in values])

    def text_room(self) -> float | None:
        """Pixels a y tick label may be wide on an axis of fixed width (pyqtgraph drops
        a label that does not fit, silently), None when the axis grows to fit."""
        if self.orientation not in ("left", "right") or self.fixedWidth is None:
            return None
        return self.fixedWidth - max(0, self.style["tickLength"]) - self.style["tickTextOffset"][0]

    def width_for(self, texts: Sequence[str]) -> int:
        """The fixed width (pixels) that leaves room for every label in ``texts``."""
        metrics = QFontMetricsF(self.tick_font())
        widest = max(metrics.horizontalAdvance(t) for t in texts)
        return math.ceil(widest + max(0, self.style["tickLength"]) + self.style["tickTextOffset"][0] + 1)

    def fits(self, values: Sequence[float], px_per_decade: float) -> bool:
        """Whether labels at ``values`` (log10 units, sorted) fit in the axis and leave
        :data:`LABEL_GAP` pixels between each other with this axis's font."""
        metrics = QFontMetricsF(self.tick_font())
        texts = labels([10.0**v for v in values])
        room = self.text_room()
        if room is not None and any(metrics.horizontalAdvance(t) > room for t in texts):
            return False
        if self.orientation in ("left", "right"):
            extents = [metrics.height()] * len(texts)
        else:
            extents = [metrics.horizontalAdvance(t) for t in texts]
        for i in range(1, len(values)):
            room = (values[i] - values[i - 1]) * px_per_decade
            if room < (extents[i] + extents[i - 1]) / 2 + LABEL_GAP:
                return False
        return True

    def _labelled(self, lo: float, hi: float, px_per_decade: float) -> list[float] | None:
        candidates = [_multiples(lo, hi, subs) for subs in MANTISSA_SETS]
        decades = candidates[-1]
        candidates += [[d for d in decades if round(d) % step == 0] for step in DECADE_STEPS]
        for values in candidates:
            if len(values) >= 2 and self.fits(values, px_per_decade):
                return values
        # no two labels fit (a short axis): one decade still tells the scale
        return decades[:1] if decades and self.fits(decades[:1], px_per_decade) else None

    def _linear(self, lo: float, hi: float, size: float) -> list[float]:
        """Evenly spaced values whose labels fit (the base class's linear spacing, or
        2, 5, 10... times it); else the roundest value in view."""
        a, b = 10.0**lo, 10.0**hi
        levels = super().tickSpacing(a, b, size)
        for spacing in [levels[0][0] * k for k in (1, 2, 5, 10)] if levels else []:
            values = np.arange(math.ceil(a / spacing), math.floor(b / spacing) + 1) * spacing
            logs = [math.log10(v) for v in values if v > 0]
            if len(logs) >= 2 and self.fits(logs, size / (hi - lo)):
                return logs
        for digits in range(1, 7):
            centre = math.log10(float(f"{10.0 ** ((lo + hi) / 2):.{digits}g}"))
            if lo <= centre <= hi:
                return [centre] if self.fits([centre], 1.0) else []
        return []


def _multiples(lo: float, hi: float, subs: Sequence[int]) -> list[float]:
    """log10 of ``s * 10**d`` for every ``s`` in ``subs`` and decade ``d``, within
    ``lo..hi``, sorted."""
    out = []
    for d in range(math.floor(lo), math.ceil(hi) + 1):
        out += [d + math.log10(s) for s in subs if lo - 1e-9 <= d + math.log10(s) <= hi + 1e-9]
    return sorted(out)


def _min_gap(subs: Sequence[int]) -> float:
    """The smallest distance (decades) between ticks at ``subs`` times every decade."""
    logs = [math.log10(s) for s in subs] + [1.0]
    return min(b - a for a, b in zip(logs, logs[1:]))


def _near(value: float, values: Sequence[float]) -> bool:
    return any(abs(value - v) < 1e-9 for v in values)
