"""Studios made and closed in one process leave nothing behind that a later paint can reach.

Two studio windows made and closed, then a latent inspector painted, once crashed the
process in pyqtgraph's ``ImageItem.paint`` (a test-order dependency). What outlived the
windows: each closed window with its plots, their term -> curve dicts full of
PlotDataItems whose C++ side was deleted with the window, kept by the window's own
``gc.freeze()`` (a frozen object is never collected) and, until the next event loop turn,
by the slot proxies of its signal connections. A closed window's views now take their
items out of their plots and drop their curve dicts, so whatever keeps a closed window
holds no Python wrapper over a plot item Qt deleted (docs/reliability.md).
"""

from __future__ import annotations

import gc
import weakref

import numpy as np
import pyqtgraph as pg
import pytest
from PyQt6 import sip

from tests.widgets.conftest import FakeRecord, FakeSnapshot, shown

#: two studio windows: about 5 s on an idle 2-core machine, 10 s on a loaded one
pytestmark = [pytest.mark.gui, pytest.mark.slow]


def _plot_items(window) -> list[pg.PlotDataItem]:
    """Every curve the window's plots hold now."""
    p = window.plots
    return [
        *p.iter_curves.items.values(),
        *p.history_curves.items.values(),
        p.ms_curve,
        p.iter_curve,
        *window.method_errors.curves.values(),
    ]


def _open_and_close(qtbot, tmp_path, motion, name: str):
    """A studio that solved and drew a few frames, closed as the ``studio`` fixture closes it.

    Returns the window (still referenced, as a pending slot proxy or a user's variable may
    reference it) and weak references to the curves it drew.
    """
    from PyQt6.QtCore import QEvent, QSettings
    from PyQt6.QtWidgets import QApplication

    from app.main_window import MainWindow

    settings = QSettings(str(tmp_path / f"{name}.ini"), QSettings.Format.IniFormat)
    window = MainWindow(settings=settings, engine="thread")
    window.session.set_motion(motion)
    window.resize(1280, 800)
    window.show()
    qtbot.waitUntil(
        lambda: len(window.plots.history_curves.items) > 1 and bool(window.method_errors.curves), timeout=20000
    )
    curves = [weakref.ref(c) for c in _plot_items(window)]
    window.undo.set_clean()
    window.close()
    QApplication.processEvents()
    window.deleteLater()
    QApplication.sendPostedEvents(None, QEvent.Type.DeferredDelete.value)
    assert sip.isdeleted(window)
    return window, curves


def _deleted(refs) -> list[str]:
    return [type(c).__name__ for c in (r() for r in refs) if c is not None and sip.isdeleted(c)]


def test_closed_studios_leave_no_deleted_plot_item_reachable_and_an_inspector_paints_after(
    qtbot, tmp_path, synthetic_motion, monkeypatch
):
    from PyQt6.QtWidgets import QMessageBox

    from widgets.latent_inspector import LatentInspector

    for kind in ("critical", "warning", "information", "question"):
        monkeypatch.setattr(QMessageBox, kind, lambda *a, _k=kind, **k: pytest.fail(f"unexpected {_k}: {a[1:3]}"))
    first, first_curves = _open_and_close(qtbot, tmp_path, synthetic_motion, "first")
    # the closed window is still referenced here: its views hold no item Qt deleted
    assert not _deleted([weakref.ref(c) for c in _plot_items(first)])
    assert not first.plots.iter_curves.items and not first.plots.history_curves.items
    assert not first.method_errors.curves
    assert not _deleted(first_curves)
    windows = [weakref.ref(first)]
    del first
    second, second_curves = _open_and_close(qtbot, tmp_path, synthetic_motion, "second")
    windows.append(weakref.ref(second))
    del second

    qtbot.wait(50)  # one event loop turn: Qt deletes the closed windows' slot proxies
    gc.collect()
    assert not _deleted(first_curves + second_curves)
    # the windows themselves may live on (frozen by the next window's gc.freeze()):
    # what they still reference is no deleted plot item
    for window in (r() for r in windows):
        if window is not None:
            assert not _deleted([weakref.ref(c) for c in _plot_items(window)])

    inspector = shown(qtbot, LatentInspector(), 430, 330)
    latents = [np.linspace(-1, 1, 24) * k for k in range(6)]
    history = tuple(FakeRecord(k, 1, 1.0, {}, z) for k, z in enumerate(latents))
    inspector.update_snapshot(FakeSnapshot(seq=2, frame=5, latent=latents[-1], history=history))
    inspector.repaint()
    image = inspector.grab().toImage()
    assert not image.isNull() and inspector.strip.image.shape == (6, 24)
