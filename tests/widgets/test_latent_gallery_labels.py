"""The gallery's cell labels at the sizes the Latent map dock takes: none overlaps another
or the figures of the row below; shortened, then hidden, only as the cells shrink."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from PyQt6.QtCore import QPointF
from PyQt6.QtWidgets import QApplication

from engine import skeleton as sk
from tests.widgets.conftest import shown
from tests.widgets.test_latent_views import _detail
from widgets.latent_gallery import CELL_H, COLUMNS, LatentGallery, front_view

#: Joints with the longest names lead every dimension's motion.
LONG = [sk.JOINT_INDEX[n] for n in ("lowerback", "upperneck", "lclavicle", "rshoulder")]


def long_named_detail():
    d = _detail()
    motion = np.zeros((24, sk.NUM_JOINTS))
    for k in range(24):
        motion[k, LONG[k % len(LONG)]] = 1.0
    return dataclasses.replace(d, motion=motion)


def drawn(w):
    for _ in range(3):
        QApplication.processEvents()
    vb = w.plot.getPlotItem().getViewBox()
    return vb, [(k, t.sceneBoundingRect()) for k, t in enumerate(w.labels) if t.isVisible()]


@pytest.mark.parametrize("size", [(300, 250), (380, 300), (476, 330), (600, 450), (900, 700)])
def test_no_label_overlaps_another_or_the_row_below(qtbot, size):
    w = shown(qtbot, LatentGallery(), *size)
    detail = long_named_detail()
    w.set_detail(detail)
    vb, rects = drawn(w)
    touching = [(a, b) for i, (a, ra) in enumerate(rects) for b, rb in rects[i + 1 :] if ra.intersects(rb)]
    assert not touching, f"labels overlap at {size}: {touching}"
    sweep = np.asarray(detail.sweep)
    for k, rect in rects:
        below = k + COLUMNS
        if below >= len(w.labels):
            continue
        head = float(front_view(sweep[below])[..., 1].max()) - (below // COLUMNS) * CELL_H
        bottom = vb.mapSceneToView(QPointF(rect.center().x(), rect.bottom())).y()
        assert bottom > head, f"the label of d{k} reaches into the figures of d{below} at {size}"


def test_labels_are_shortened_then_hidden_only_as_the_cells_shrink(qtbot):
    w = shown(qtbot, LatentGallery(), 900, 700)
    w.set_detail(long_named_detail())
    _, rects = drawn(w)
    assert len(rects) == 24 and all("\n" in t.textItem.toPlainText() for t in w.labels), "full labels when roomy"
    w.resize(476, 330)  # the Latent map dock's size in the studio
    _, rects = drawn(w)
    assert [w.labels[k].textItem.toPlainText() for k, _ in rects] == [f"d{k}" for k in range(24)]
    assert w.labels[0].toolTip() == "d0: moves lowerback"
    w.resize(900, 700)
    _, rects = drawn(w)
    assert len(rects) == 24 and all("\n" in t.textItem.toPlainText() for t in w.labels), "full again"
