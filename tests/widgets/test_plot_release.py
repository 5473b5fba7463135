"""A closed plot view holds no plot item: it takes them out of its plots and drops its
term -> curve dicts in ``closeEvent`` (widgets.plots.release), so nothing of ours keeps a
Python wrapper over an item Qt deletes with the window (docs/reliability.md)."""

from __future__ import annotations

import numpy as np
import pyqtgraph as pg
import pytest
from PyQt6 import sip
from PyQt6.QtCore import QObject

from tests.widgets.conftest import FakeRecord, shown
from widgets.latent_forces import LatentForces
from widgets.latent_gallery import LatentGallery
from widgets.latent_inspector import LatentInspector
from widgets.latent_map import LatentMapPlot
from widgets.latent_readouts import LatentReadouts
from widgets.method_errors import MethodErrorPlot
from widgets.plots import LossPlots


def _records(n: int) -> tuple[FakeRecord, ...]:
    return tuple(FakeRecord(f, 2, 3.0, {"total": 0.1, "pos:root": 0.05}, np.full(24, 0.1 * f)) for f in range(n))


def _plots(view) -> list[pg.PlotWidget]:
    return [w for w in vars(view).values() if isinstance(w, pg.PlotWidget)]


def _close_and_check_released(view) -> None:
    """Close ``view`` twice (as a window's close and the test's teardown may): its plots
    are empty and none of the items they held was deleted or left in a scene."""
    items = [item for plot in _plots(view) for item in plot.getPlotItem().items]
    assert items, "the view has no plot item to release"
    view.close()
    view.close()
    assert all(plot.getPlotItem().items == [] for plot in _plots(view))
    assert not any(sip.isdeleted(item) or item.scene() is not None for item in items)


@pytest.mark.parametrize("make", [LossPlots, LatentInspector, MethodErrorPlot], ids=lambda c: c.__name__)
def test_closing_a_plot_view_takes_every_item_out_of_its_plots(qtbot, fake_snapshot, make):
    view = shown(qtbot, make(), 640, 300)
    history = _records(5)
    view.update_snapshot(fake_snapshot(seq=2, frame=4, latent=history[-1].latent, history=history))
    _close_and_check_released(view)
    # the view's own dicts and those of its plain helpers (the term -> curve dicts)
    held = list(vars(view).values())
    held += [vars(v).get("items") for v in held if not isinstance(v, QObject) and hasattr(v, "__dict__")]
    curves = [c for d in held if isinstance(d, dict) for c in d.values() if isinstance(c, pg.PlotDataItem)]
    assert not curves, "a curve dict survived the close"


@pytest.mark.parametrize("make", [LatentMapPlot, LatentReadouts, LatentForces, LatentGallery], ids=lambda c: c.__name__)
def test_closing_a_latent_map_view_takes_every_item_out_of_its_plots(qtbot, make):
    _close_and_check_released(shown(qtbot, make(), 640, 300))
