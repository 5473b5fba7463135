"""The studio's latent map dock end to end: real clicks on the map decode a ghost pose or
seek a frame, *Inspect this frame* brings the term forces, a method without a latent says
so (a real engine thread; DragPoser with the shipped models)."""

from __future__ import annotations

import time

import numpy as np
import pytest
from PyQt6.QtCore import Qt
from PyQt6.QtWidgets import QApplication, QDockWidget


def _show_map(window):
    views = window.latent_views
    views.dock.raise_()
    views.tabs.setCurrentIndex(0)
    QApplication.processEvents()
    return views


def _click(views, x, y):
    w = views.map
    w.plot.repaint()
    QApplication.processEvents()
    from PyQt6.QtTest import QTest
    from pytestqt.qtbot import QtBot  # noqa: F401 (the fixture's type; clicks go through QTest)

    QTest.mouseClick(w.plot.viewport(), Qt.MouseButton.LeftButton, pos=w.to_widget(x, y).toPoint())


def test_the_dock_says_when_the_method_has_no_latent(studio, qtbot):
    assert studio.session.method == "ik"
    dock = studio.findChild(QDockWidget, "Latent map")
    assert dock is studio.latent_views.dock
    views = _show_map(studio)
    qtbot.waitUntil(lambda: views.map.note.isVisible(), timeout=10000)
    assert "ik has no latent space" in views.map.note.text()


def test_map_clicks_decode_and_seek_with_dragposer(studio, qtbot):
    s = studio.session
    s.set_method("dragposer")
    s.play()
    qtbot.waitUntil(
        lambda: (
            s.latest is not None
            and s.latest.latent_view is not None
            and len([r for r in s.latest.history if r.readouts]) >= 10
        ),
        timeout=90000,
    )
    s.pause()
    views = _show_map(studio)
    qtbot.waitUntil(lambda: len(views.map.xy) >= 10, timeout=10000)
    # a click beside the trajectory decodes that point as the debug pose
    view = s.latest.latent_view
    seq = s.latest.seq
    target = view.xy + [0.8, 0.8]
    t0 = time.perf_counter()
    _click(views, *target)
    qtbot.waitUntil(lambda: s.latest.seq > seq and s.latest.decoded is not None, timeout=10000)
    decode_ms = 1000 * (time.perf_counter() - t0)
    print(f"map click to decoded pose: {decode_ms:.0f} ms")
    assert not np.allclose(s.latest.decoded, s.latest.positions, atol=1e-3)
    # a click on a trajectory point goes to its frame, and the trajectory stays (the seek
    # back restarts the engine's history)
    solved = len(views.map.xy)
    frame = int(views.map.frames[3])
    _click(views, *views.map.xy[3])
    qtbot.waitUntil(lambda: s.frame == frame, timeout=5000)
    qtbot.waitUntil(lambda: s.latest.frame == frame and s.latest.latent_view is not None, timeout=30000)
    qtbot.waitUntil(lambda: views.map._drawn[0] == s.latest.seq, timeout=10000)
    assert len(s.latest.history) == 1 and len(views.map.xy) == solved
    # Inspect this frame: the forces arrive and are drawn
    views.tabs.setCurrentIndex(1)
    qtbot.mouseClick(views.forces.inspect_button, Qt.MouseButton.LeftButton)
    qtbot.waitUntil(lambda: s.latest.latent_detail is not None, timeout=30000)
    qtbot.waitUntil(lambda: views.forces.detail is not None, timeout=10000)
    d = views.forces.detail
    assert d.frame == frame and len(views.forces.norm_bars.opts["width"]) == len(d.names)
    assert any(n.startswith("sensor:") for n in d.names)
    qtbot.waitUntil(lambda: len(views.map.force_lines) == len(d.names), timeout=5000)  # drawn on the map too
    # the Latent panel's A and B: their blend's path appears on the map
    qtbot.waitUntil(lambda: studio.latent.latent is not None, timeout=5000)
    studio.latent.capture_a.click()
    studio.latent.stored["b"] = studio.latent.stored["a"] + 0.5
    views.tabs.setCurrentIndex(0)
    s.step(1)
    qtbot.waitUntil(
        lambda: views.map.blend.getData()[0] is not None and len(views.map.blend.getData()[0]) == 2, timeout=10000
    )


def test_the_dock_in_front_is_remembered(studio, qtbot):
    from PyQt6.QtWidgets import QTabBar

    from app.latent_views import RAISED

    bar = next(b for b in studio.findChildren(QTabBar) if "Latent map" in [b.tabText(i) for i in range(b.count())])
    index = [bar.tabText(i) for i in range(bar.count())].index("Latent map")
    qtbot.mouseClick(bar, Qt.MouseButton.LeftButton, pos=bar.tabRect(index).center())
    qtbot.waitUntil(lambda: studio.settings.value(RAISED, False, type=bool), timeout=10_000)
    latent = [bar.tabText(i) for i in range(bar.count())].index("Latent")
    qtbot.mouseClick(bar, Qt.MouseButton.LeftButton, pos=bar.tabRect(latent).center())
    qtbot.waitUntil(lambda: not studio.settings.value(RAISED, True, type=bool), timeout=10_000)


def test_a_map_behind_the_latent_dock_is_not_redrawn(studio, qtbot):
    views = _show_map(studio)
    qtbot.waitUntil(lambda: views.map._drawn[0] == studio.session.latest.seq, timeout=10000)
    studio.findChild(QDockWidget, "Latent").raise_()
    QApplication.processEvents()
    seq = studio.session.latest.seq
    drawn = views.map._drawn[0]
    studio.session.step(1)
    qtbot.waitUntil(lambda: studio.session.latest.seq > seq, timeout=10000)
    qtbot.wait(1200)  # more than the panel's interval
    assert views.map._drawn[0] == drawn


def test_the_tabs_are_built_when_the_dock_is_first_shown_and_flags_reach_the_timeline_before(studio, qtbot):
    """Behind the Latent dock (where it starts) the map dock builds nothing, yet the flag
    verdicts of the solved frames still mark the timeline; raised, it shows its tabs."""
    from types import SimpleNamespace

    views = studio.latent_views
    assert views.tabs is None and views.map is None and views.forces is None and views.gallery is None

    def entry(frame, flagged):
        return SimpleNamespace(frame=frame, ms=1.0, iterations=1, readouts={"flagged": float(flagged)})

    views._update_map(
        SimpleNamespace(seq=10**6, frame=3, history=(entry(2, True), entry(3, False)), opened=studio.session.opened)
    )
    assert studio.timeline.slider.marks() == (2,)
    assert views.tabs is None
    views = _show_map(studio)
    assert views.tabs is not None and views.map.isVisible() and views.readouts.isVisible()
    assert views.tabs.count() == 3 and views.readouts.next_flagged() == 2
    qtbot.waitUntil(lambda: views.map._drawn[0] == studio.session.latest.seq, timeout=10000)  # drawn once shown


def _map_of_eight_solved_frames(studio, qtbot):
    """Play DragPoser until 8 frames have readouts, pause and show the Map tab (its views)."""
    s = studio.session
    s.set_method("dragposer")
    s.play()
    qtbot.waitUntil(
        lambda: s.latest.latent_view is not None and len([r for r in s.latest.history if r.readouts]) >= 8,
        timeout=90000,
    )
    s.pause()
    views = _show_map(studio)
    qtbot.waitUntil(lambda: len(views.map.xy) >= 8, timeout=10000)
    return views


def test_another_clip_empties_the_map_even_while_its_tab_is_hidden(studio, qtbot, synthetic_motion):
    """Opened while the Gallery tab is in front, another clip's first frame is what the
    Map tab shows when clicked, not the previous clip's frame and trajectory."""
    s = studio.session
    views = _map_of_eight_solved_frames(studio, qtbot)
    bar = views.tabs.tabBar()
    qtbot.mouseClick(bar, Qt.MouseButton.LeftButton, pos=bar.tabRect(2).center())  # Gallery
    assert views.tabs.currentIndex() == 2
    s.set_motion(synthetic_motion.slice(40, 70))
    qtbot.waitUntil(lambda: s.latest.num_frames == 30 and s.latest.latent_view is not None, timeout=60000)
    qtbot.wait(700)  # the draw scheduler has handed the snapshot over (to the hidden tab)
    qtbot.mouseClick(bar, Qt.MouseButton.LeftButton, pos=bar.tabRect(0).center())  # Map
    qtbot.waitUntil(lambda: views.map._drawn[0] == s.latest.seq, timeout=5000)
    x, y = views.map.current.getData()
    assert (x[0], y[0]) == pytest.approx(tuple(s.latest.latent_view.xy))
    assert list(views.map.frames) == sorted({r.frame for r in s.latest.history if r.readouts})
    assert f"frame {s.latest.frame}:" in views.readouts.label.text()


def _axes_agree(views) -> bool:
    """The map's axes label the range its view box shows (ticks drawn from ``axis.range``)."""
    plot = views.map.plot.getPlotItem()
    (x0, x1), (y0, y1) = plot.getViewBox().viewRange()
    bottom, left = plot.getAxis("bottom").range, plot.getAxis("left").range
    return np.allclose(bottom, (x0, x1)) and np.allclose(left, (y0, y1))


def test_the_map_axes_follow_zoom_to_the_clip(studio, qtbot, synthetic_motion):
    """Zoom to the clip moves the view onto the trajectory, and the axes' numbers move with
    it: after another clip's first frame (a view 1.6 units tall) they read that range, not
    the whole map's -20..20 they read before."""
    s = studio.session
    views = _map_of_eight_solved_frames(studio, qtbot)
    assert views.map.zoom.isChecked()
    qtbot.waitUntil(lambda: _axes_agree(views), timeout=10_000)
    s.set_motion(synthetic_motion.slice(40, 70))
    qtbot.waitUntil(lambda: s.latest.num_frames == 30 and s.latest.latent_view is not None, timeout=60000)
    qtbot.waitUntil(lambda: views.map._drawn[0] == s.latest.seq, timeout=5000)
    (_, _), (y0, y1) = views.map.plot.getPlotItem().getViewBox().viewRange()
    assert y1 - y0 < 3.0  # zoomed onto the one solved frame
    QApplication.processEvents()
    assert _axes_agree(views)
    # unticked and ticked again with the mouse: the view and its axes come back to the clip
    box = views.map.zoom
    qtbot.mouseClick(box, Qt.MouseButton.LeftButton, pos=box.rect().center())
    qtbot.mouseClick(box, Qt.MouseButton.LeftButton, pos=box.rect().center())
    assert box.isChecked()
    QApplication.processEvents()
    assert _axes_agree(views)


def test_the_forces_tab_says_it_is_empty_after_the_next_solve(studio, qtbot):
    """An inspection holds until the next solve; after a step the Forces tab names no term
    or iteration of the frame it left (its bars gone, the titles and term ticks were
    still there) and says what fills it, as the Gallery does."""
    from PyQt6.QtWidgets import QToolButton

    s = studio.session
    s.set_method("dragposer")
    s.play()
    qtbot.waitUntil(lambda: s.latest.latent_view is not None and s.frame >= 5, timeout=90000)
    views = _show_map(studio)
    views.tabs.setCurrentIndex(1)
    forces = views.forces
    qtbot.mouseClick(forces.inspect_button, Qt.MouseButton.LeftButton)
    qtbot.waitUntil(lambda: forces.detail is not None, timeout=30000)
    assert forces.dim_plot.getPlotItem().titleLabel.text.startswith("force of ")
    assert forces.info.text().startswith(f"frame {forces.detail.frame},")
    step = next(b for b in studio.timeline.findChildren(QToolButton) if b.toolTip().startswith("Next frame"))
    qtbot.mouseClick(step, Qt.MouseButton.LeftButton)
    qtbot.waitUntil(lambda: forces.detail is None, timeout=30000)
    assert forces.dim_plot.getPlotItem().titleLabel.text == "per latent dimension: none"
    assert forces.term_axis.names == ()  # no term names left
    assert forces.info.text().startswith("Empty until Inspect this frame")


@pytest.mark.parametrize("size", ["1600x980", "minimum"])
def test_the_readouts_frame_label_is_inside_the_dock(studio, qtbot, size):
    """The Map tab fits its dock at the default window (1600 x 980) and at the minimum
    size, with a readout line wrapped to three lines: the readouts' "frame" label lies
    inside the dock (a wrapped line asks for its height, the map gives way), and the y
    axis says its units."""
    from PyQt6.QtCore import QPoint

    s = studio.session
    s.pause()
    views = _show_map(studio)
    r = views.readouts
    # the longest line the readouts show: a frame flagged when solved before (three lines)
    r.label.setText(
        "frame 149: nearest 0.96 &le; 3.20, norm 2.34 &le; 6.39, prior 0.89<br><span>flagged when solved"
        " before (nearest 3.41 &gt; 3.20, norm 2.34 &le; 6.39); solved again from here it is not</span>"
    )
    studio.resize(*((1600, 980) if size == "1600x980" else (1, 1)))  # (1, 1): the minimum size
    qtbot.waitUntil(lambda: r.plot.isVisible() and r.plot.height() > 0, timeout=5000)
    for _ in range(5):
        QApplication.processEvents()
    dock = views.dock
    plot_bottom = r.plot.mapTo(dock, QPoint(0, r.plot.height())).y()
    assert plot_bottom <= dock.height(), (
        f"the plot runs {plot_bottom - dock.height()} px past the dock at {studio.size()}"
    )
    axis = r.plot.getAxis("bottom")
    label = axis.label.mapRectToScene(axis.label.boundingRect())
    assert label.bottom() - 5 <= r.plot.height()  # pyqtgraph nudges the label's box 5 px down
    assert "latent units" in r.plot.getAxis("left").labelText
