"""Loss terms: one colour each, distinct however many, the same from frame to frame."""

from __future__ import annotations

import itertools
import math

from widgets import style
from widgets.plots import LossPlots

SIX = ("root", "upperneck", "lwrist", "rwrist", "lankle", "rankle")


def _terms() -> dict[str, float]:
    terms = {"total": 1.0, **{f"{k}:{j}": 0.1 for j in SIX for k in ("pos", "rot")}}
    # six trackers with a look-at, a floor, a distance and a pin: 18 terms and the total
    return {**terms, "temporal_prior": 0.01, "look_at": 0.02, "floor": 0.03, "distance": 0.04, "pin": 0.05}


def test_every_term_has_its_own_colour_and_keeps_it(qtbot, fake_snapshot):
    p = LossPlots()
    qtbot.addWidget(p)
    terms = _terms()
    p.update_snapshot(fake_snapshot(seq=1, frame=1, losses=(terms, terms)))
    first = {n: p.colours[n] for n in terms}
    rgb = [style.hex_to_rgb(c) for c in first.values()]
    closest = min(math.dist(a, b) for a, b in itertools.combinations(rgb, 2))
    assert closest > 30, f"two terms look alike (RGB distance {closest:.0f})"
    p.update_snapshot(fake_snapshot(seq=2, frame=2, losses=(terms, terms)))
    assert {n: p.colours[n] for n in terms} == first
