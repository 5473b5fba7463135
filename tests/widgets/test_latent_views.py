"""The latent-debugging widgets with real mouse events: the map's hover and clicks, the
readouts' next flagged frame, the term forces' bars and the dimension gallery."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import pytest
from PyQt6.QtCore import QPoint, Qt
from PyQt6.QtTest import QTest
from PyQt6.QtWidgets import QApplication, QLabel

from engine import skeleton as sk
from engine.latent.projection import default_map
from engine.studio.latent_views import LatentDetail, LatentView
from engine.studio.snapshot import HistoryEntry
from tests.widgets.conftest import shown
from widgets.latent_forces import LatentForces, conflicts
from widgets.latent_gallery import LatentGallery, front_view
from widgets.latent_map import LatentMapPlot
from widgets.latent_readouts import LatentReadouts


@dataclass
class Snap:
    """The fields the latent views read from ``engine.studio.snapshot.Snapshot``."""

    seq: int
    frame: int
    history: tuple
    latent_view: LatentView | None = None
    latent_detail: LatentDetail | None = None
    latent_note: str = ""
    playing: bool = False
    extra: dict = field(default_factory=dict)


def _snap(n: int = 40, flagged: tuple[int, ...] = (), seq: int = 1, frame: int | None = None, ms: float = 2.0) -> Snap:
    """Frames 0..n-1 on a line across the map, frame ``frame`` (default last) on screen,
    each solved in ``ms`` (a solve's wall time tells its entry from an earlier solve's)."""
    xs = np.linspace(-2.0, 2.0, n)
    hist = tuple(
        HistoryEntry(
            f,
            5,
            ms,
            {"total": 1.0},
            np.full(24, 0.1 * f),
            {
                "x": xs[f],
                "y": 0.5 * xs[f],
                "nearest": 1.0 + 0.01 * f,
                "norm": 3.0,
                "predictor": 0.4,
                "flagged": float(f in flagged),
            },
        )
        for f in range(n)
    )
    f = n - 1 if frame is None else frame
    r = hist[f].readouts
    path = np.array([[r["x"] - 0.6, r["y"] - 0.9], [r["x"] - 0.2, r["y"] - 0.3], [r["x"], r["y"]]])
    view = LatentView(
        f, np.full(24, 0.1 * f), np.array([r["x"], r["y"]]), path, "predictor", r["nearest"], 3.0, 0.4, f in flagged
    )
    return Snap(seq, f, hist, view)


@pytest.fixture
def latent_map(qtbot):
    w = shown(qtbot, LatentMapPlot(), 420, 420)
    m = default_map()
    w.set_map(m.density, m.extent, m.explained)
    return w


def _at(w: LatentMapPlot, x: float, y: float) -> QPoint:
    """Where map point ``(x, y)`` is on screen, after the plot's layout settled (the axes
    take their widths at the first paint, which moves the view box; on a loaded machine
    that can take more than one round of events): the same answer twice in a row."""
    last = None
    for _ in range(50):
        w.plot.repaint()
        QApplication.processEvents()
        here = w.to_widget(x, y).toPoint()
        if here == last:
            return here
        last = here
        QTest.qWait(20)
    return here


def test_hover_over_empty_map_and_over_a_frame(latent_map, qtbot):
    latent_map.update_snapshot(_snap())
    points, frames = [], []
    latent_map.pointHovered.connect(lambda x, y: points.append((x, y)))
    latent_map.frameHovered.connect(frames.append)
    qtbot.mouseMove(latent_map.plot.viewport(), _at(latent_map, 1.0, -2.5))
    px, py = latent_map.plot.getPlotItem().getViewBox().viewPixelSize()
    near = pytest.approx((1.0, -2.5), abs=2 * max(px, py))
    # under Xvfb the display's own pointer also sends moves (where it rested, or where the
    # window appeared under it), before or after the test's move: the test's point must be among them
    # (generous timeouts: with both cores busy beside the suite an event can take seconds)
    qtbot.waitUntil(lambda: any(p == near for p in points), timeout=10_000)
    target = latent_map.xy[10]
    qtbot.wait(100)  # under Xvfb the first move's events are still arriving
    qtbot.mouseMove(latent_map.plot.viewport(), _at(latent_map, *target))
    qtbot.waitUntil(lambda: 10 in frames, timeout=10_000)


def test_clicks_seek_a_frame_or_pick_a_point(latent_map, qtbot):
    latent_map.update_snapshot(_snap())
    points, frames = [], []
    latent_map.pointClicked.connect(lambda x, y: points.append((x, y)))
    latent_map.frameClicked.connect(frames.append)
    qtbot.mouseClick(latent_map.plot.viewport(), Qt.MouseButton.LeftButton, pos=_at(latent_map, *latent_map.xy[25]))
    assert frames == [25] and points == []
    qtbot.mouseClick(latent_map.plot.viewport(), Qt.MouseButton.LeftButton, pos=_at(latent_map, -1.0, 2.0))
    px, py = latent_map.plot.getPlotItem().getViewBox().viewPixelSize()
    assert frames == [25] and points[-1] == pytest.approx((-1.0, 2.0), abs=2 * max(px, py))


def test_map_draws_trajectory_path_and_flags(latent_map):
    latent_map.update_snapshot(_snap(flagged=(3, 7)))
    assert len(latent_map.points.data) == 40
    assert len(latent_map.flags.data) == 2
    assert latent_map.path.getData()[0].shape == (3,)
    assert latent_map.start_label.textItem.toPlainText() == "start: predictor"
    x, y = latent_map.current.getData()
    assert (x[0], y[0]) == pytest.approx(tuple(latent_map.xy[-1]))
    # colour by time: the first point dark, the last bright
    first, last = latent_map.points.data[0]["brush"].color(), latent_map.points.data[-1]["brush"].color()
    assert first.lightness() < last.lightness()


def test_a_method_without_a_latent_is_said(latent_map):
    snap = Snap(2, 0, (HistoryEntry(0, 1, 1.0, {"total": 1.0}),), None, None, "ik has no latent space: ...")
    latent_map.update_snapshot(snap)
    assert latent_map.note.isVisible() and "ik has no latent space" in latent_map.note.text()
    assert len(latent_map.points.data) == 0


def test_next_flagged_frame_seeks_and_marks(qtbot):
    w = shown(qtbot, LatentReadouts(), 420, 250)
    marks, seeks = [], []
    w.flagsChanged.connect(marks.append)
    w.seekRequested.connect(seeks.append)
    w.update_snapshot(_snap(flagged=(5, 30), frame=10))
    assert marks[-1] == [5, 30]
    qtbot.mouseClick(w.next_button, Qt.MouseButton.LeftButton)
    assert seeks == [30]
    w.update_snapshot(_snap(n=12, flagged=(5,), seq=2, frame=11))  # the engine's history restarted
    qtbot.mouseClick(w.next_button, Qt.MouseButton.LeftButton)
    assert seeks == [30, 30]  # frame 30's verdict is remembered across the restart
    w.clear()
    assert marks[-1] == [] and w.next_flagged() is None


def _detail(influence: bool = True) -> LatentDetail:
    forces = np.zeros((3, 3, 24))
    forces[:, 0, 0] = 1.0
    forces[:, 1, 0] = -2.0  # against the first
    forces[:, 2, 5] = 0.5
    rest = np.asarray(sk.Skeleton.canonical().rest_positions())
    sweep = np.stack([np.stack([rest + [0, 0, 0.1 * o] for o in (-1, 0, 1)]) for _ in range(24)])
    motion = np.zeros((24, 22))
    motion[:, sk.JOINT_INDEX["lwrist"]] = 0.2
    return LatentDetail(
        7,
        ("sensor:lwrist", "look_at", "temporal_prior"),
        forces,
        forces[..., :2],
        sweep,
        motion,
        "lwrist" if influence else "",
        np.arange(24.0) if influence else None,
        800.0,
    )


def test_forces_bars_in_the_loss_plots_colours(qtbot):
    colours = {"total": "#ffffff", "sensor:lwrist": "#123456"}
    w = shown(qtbot, LatentForces(colours), 420, 400)
    asked = []
    w.inspectRequested.connect(asked.append)
    w.joint.setCurrentIndex(w.joint.findData("lwrist"))
    qtbot.mouseClick(w.inspect_button, Qt.MouseButton.LeftButton)
    assert asked == ["lwrist"]
    w.set_detail(_detail())
    norms = w.norm_bars.opts["width"]  # horizontal bars: a norm is a bar's length
    assert list(norms) == pytest.approx([1.0, 2.0, 0.5])
    assert w.norm_bars.opts["brushes"][0] == "#123456"  # the shared colour
    assert "look_at" in colours  # a new term gets its colour in the shared dict
    assert "sensor:lwrist vs look_at" in w.info.text()
    assert list(w.dim_bars.opts["height"]) == pytest.approx(np.arange(24.0))  # the joint's influence first
    w.term.setCurrentIndex(w.term.findData("temporal_prior"))
    assert w.dim_bars.opts["height"][5] == pytest.approx(0.5)
    assert conflicts(_detail().forces[0], _detail().names) == ["sensor:lwrist vs look_at"]


def test_gallery_draws_every_dimension(qtbot):
    w = shown(qtbot, LatentGallery(), 500, 400)
    w.set_detail(_detail())
    assert len(w.labels) == 24 and w.labels[0].toolTip() == "d0: moves lwrist"  # shown shortened at this size
    x, _ = w.lines[0].getData()
    assert len(x) == 24 * 2 * (sk.NUM_JOINTS - 1)
    assert w.influential == [23, 22, 21, 20, 19]
    w.set_detail(None)
    assert w.labels == [] and len(w.lines[0].getData()[0] or []) == 0


def test_front_view_turns_the_hips_across():
    rest = np.asarray(sk.Skeleton.canonical().rest_positions())
    c, s = np.cos(1.0), np.sin(1.0)
    turned = rest @ np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]]).T + [3, 4, 0]
    v = front_view(turned[None])[0]
    left = v[sk.JOINT_INDEX["lhip"]] - v[sk.JOINT_INDEX["rhip"]]
    hips = rest[sk.JOINT_INDEX["lhip"]] - rest[sk.JOINT_INDEX["rhip"]]
    # the whole horizontal hip line lies across the view, the heights unchanged
    assert left == pytest.approx([np.hypot(hips[0], hips[1]), hips[2]])
    assert v[0] == pytest.approx([0.0, 0.0])


def test_zoom_to_the_clip_until_the_user_zooms(latent_map, qtbot):
    latent_map.update_snapshot(_snap())
    (x0, x1), (y0, y1) = latent_map.plot.getPlotItem().getViewBox().viewRange()
    assert x0 <= -2.0 and x1 >= 2.0 and x1 - x0 < 8.0  # the clip, not the whole map (12 wide)
    assert latent_map.zoom.isChecked()
    latent_map.plot.getPlotItem().getViewBox().scaleBy((0.5, 0.5))  # as the mouse wheel does
    latent_map.plot.getPlotItem().getViewBox().sigRangeChangedManually.emit([True, True])
    assert not latent_map.zoom.isChecked()


def test_a_frame_solved_again_takes_its_new_verdict(qtbot):
    w = LatentReadouts()
    qtbot.addWidget(w)  # never shown: the verdicts alone (what the window reads while the tab is hidden)
    marks = []
    w.flagsChanged.connect(marks.append)
    first = _snap(n=10, flagged=(4,), frame=9)
    w.note_verdicts(first)
    assert marks[-1] == [4]
    again = _snap(n=10, flagged=(), seq=2, frame=9, ms=2.5)  # an edit: the frames solved again, none flagged
    w.note_verdicts(again)
    assert marks[-1] == [] and w.next_flagged() is None
    n = len(marks)
    w.note_verdicts(again)  # nothing new
    assert len(marks) == n


def test_forces_drawn_on_the_map_in_term_colours(latent_map):
    latent_map.update_snapshot(_snap())
    latent_map.set_forces(np.array([0.0, 0.0]), np.array([[1.0, 0.0], [0.0, -0.5]]), ["#ff0000", "#00ff00"])
    assert len(latent_map.force_lines) == 2
    (x0, x1), _ = latent_map.plot.getPlotItem().getViewBox().viewRange()
    xs, ys = latent_map.force_lines[0].getData()
    assert xs[1] - xs[0] == pytest.approx(0.25 * (x1 - x0))  # the longest: a quarter of the view
    xs, ys = latent_map.force_lines[1].getData()
    assert ys[1] - ys[0] == pytest.approx(-0.125 * (x1 - x0))
    assert latent_map.force_lines[1].opts["pen"].color().name() == "#00ff00"
    latent_map.set_forces(None)
    assert latent_map.force_lines == []


def test_the_a_to_b_blend_is_drawn(latent_map):
    latent_map.set_blend(np.array([0.0, 1.0]), np.array([2.0, -1.0]))
    xs, ys = latent_map.blend.getData()
    assert list(xs) == [0.0, 2.0] and list(ys) == [1.0, -1.0]
    assert latent_map.blend_labels[1].textItem.toPlainText() == "B"
    latent_map.set_blend(None, None)
    assert len(latent_map.blend.getData()[0] or []) == 0


def test_verdicts_read_only_new_entries_of_unpickled_snapshots(qtbot):
    import pickle

    w = LatentReadouts()
    qtbot.addWidget(w)
    snap = _snap(n=600, flagged=(7,))
    w.note_verdicts(snap)
    copy = pickle.loads(pickle.dumps(snap))  # as an engine process delivers it: new objects
    version = w.solved.version
    w.note_verdicts(copy)  # were every entry read again, the store would change
    assert w.solved.version == version


def _restarted(frame: int, seq: int, readouts: dict, ms: float = 9.0) -> Snap:
    """The snapshot after a seek to ``frame``: the engine's history restarted with that
    one solve, whose ``readouts`` (x, y, nearest, norm, flagged) differ from playback's."""
    r = {"predictor": 0.4, **readouts}
    entry = HistoryEntry(frame, 5, ms, {"total": 1.0}, np.full(24, 0.1), r)
    view = LatentView(
        frame,
        np.full(24, 0.1),
        np.array([r["x"], r["y"]]),
        None,
        "previous frame",
        r["nearest"],
        r["norm"],
        0.4,
        bool(r["flagged"]),
    )
    return Snap(seq, frame, (entry,), view)


def test_a_click_on_a_trajectory_point_keeps_the_trajectory(latent_map, qtbot):
    """The seek restarts the engine's history: the map still shows every frame solved."""
    latent_map.update_snapshot(_snap())
    frames = []
    latent_map.frameClicked.connect(frames.append)
    qtbot.mouseClick(latent_map.plot.viewport(), Qt.MouseButton.LeftButton, pos=_at(latent_map, *latent_map.xy[12]))
    assert frames == [12]
    x, y = latent_map.xy[12]
    latent_map.update_snapshot(_restarted(12, 2, {"x": x, "y": y, "nearest": 1.1, "norm": 3.0, "flagged": 0.0}))
    assert len(latent_map.points.data) == 40 and len(latent_map.xy) == 40
    cx, cy = latent_map.current.getData()
    assert (cx[0], cy[0]) == pytest.approx((x, y))
    latent_map.clear()  # another clip
    assert len(latent_map.points.data) == 0 and len(latent_map.current.getData()[0]) == 0


def test_next_flagged_frame_and_the_readouts_tell_one_story(qtbot):
    """The jump lands on a frame flagged in playback; solved again from here it reads
    below both thresholds: the line says both, against the thresholds."""
    w = shown(qtbot, LatentReadouts(), 620, 260)
    w.set_thresholds(3.20, 6.39)
    snap = _snap(n=40, flagged=(30,), frame=10)
    snap.history[30].readouts.update(nearest=3.45)
    w.update_snapshot(snap)
    seeks = []
    w.seekRequested.connect(seeks.append)
    qtbot.mouseClick(w.next_button, Qt.MouseButton.LeftButton)
    assert seeks == [30]
    r = snap.history[30].readouts
    w.update_snapshot(_restarted(30, 2, {"x": r["x"], "y": r["y"], "nearest": 3.08, "norm": 3.91, "flagged": 0.0}))
    text = w.label.text()
    assert "nearest 3.08 &le; 3.20" in text and "norm 3.91 &le; 6.39" in text
    assert "flagged when solved before (nearest 3.45 &gt; 3.20" in text
    assert w.next_flagged() is None  # the newest solve of frame 30 is not flagged


def test_a_cross_sits_on_the_readout_that_crossed(qtbot):
    w = shown(qtbot, LatentReadouts(), 420, 250)
    w.set_thresholds(3.2, 2.5)  # every frame's norm (3.0) is above this one
    w.update_snapshot(_snap(n=10, flagged=(4,), frame=9))
    xs, ys = w.flags.getData()
    assert list(xs) == [4.0] and list(ys) == pytest.approx([3.0])  # on the norm curve
    assert w.thresholds["norm"].pen.color().name() == "#c77dff"  # dashed in its curve's colour


def test_the_lower_force_chart_starts_on_a_term_with_force(qtbot):
    w = shown(qtbot, LatentForces(), 420, 400)
    d = _detail(influence=False)
    forces = d.forces.copy()
    forces[:, 0] = 0.0  # the first term (a met sensor) pushes nothing
    import dataclasses

    w.set_detail(dataclasses.replace(d, forces=forces, plane=forces[..., :2]))
    assert w.term.currentData() == "look_at"
    assert w.dim_bars.opts["height"][0] == pytest.approx(-2.0)
    w.term.setCurrentIndex(0)
    assert "no force" in w.dim_plot.getPlotItem().titleLabel.text


#: The terms of the default six trackers, as the Forces tab showed them
SIX_TERMS = tuple(f"sensor:{j}" for j in ("root", "upperneck", "lwrist", "rwrist", "lankle", "rankle")) + (
    "temporal_prior",
    "smooth",
)


def _drawn_names(w: LatentForces) -> list:
    """The tick labels the force-norm chart draws: (text, rect in scene coordinates)."""
    from PyQt6.QtGui import QImage, QPainter

    out = []
    image = QImage(8, 8, QImage.Format.Format_ARGB32)
    for side in ("left", "bottom"):
        axis = w.norm_plot.getAxis(side)
        painter = QPainter(image)
        try:
            _axis, _ticks, texts = axis.generateDrawSpecs(painter)
        finally:
            painter.end()
        out += [(text, axis.mapRectToScene(rect)) for rect, _flags, text in texts]
    return out


@pytest.mark.parametrize("size", [(460, 430), (460, 300)])
def test_the_term_names_of_the_force_chart_do_not_run_into_each_other(qtbot, size):
    """Seen in the Forces tab (460 px wide): the names under the bars ran into each other
    ("rankletemporal_prior"). Each name drawn has its own room, and at the panel's size
    every term is named (a short panel may name every other one; the tooltip has all)."""
    w = shown(qtbot, LatentForces(), *size)
    t, latent = len(SIX_TERMS), 24
    forces = np.random.default_rng(0).normal(size=(2, t, latent))
    import dataclasses

    w.set_detail(dataclasses.replace(_detail(False), names=SIX_TERMS, forces=forces, plane=forces[..., :2]))
    for _ in range(3):  # the charts laid out at the panel's size
        QApplication.processEvents()
    drawn = _drawn_names(w)
    rects = [r for _text, r in drawn]
    crowded = [(a[0], b[0]) for i, a in enumerate(drawn) for b in drawn[i + 1 :] if a[1].intersects(b[1])]
    assert not crowded, f"names drawn over each other: {crowded}"
    names = {text for text, _r in drawn}
    short = {n.removeprefix("sensor:") for n in SIX_TERMS}
    if size[1] >= 430:  # the tab at 1600 x 1000
        assert short <= names, f"unnamed: {short - names}"
    else:
        assert len(names & short) >= len(short) // 2
    view = w.norm_plot.sceneRect()
    assert all(view.contains(r) for r in rects)
    for n in SIX_TERMS:
        assert n in w.norm_plot.toolTip()


def test_empty_force_charts_say_why_and_show_no_axis_values(qtbot):
    """Before any inspection, and with IK, the charts have nothing to draw: they say why
    in their titles and tooltips and hide their axis values (pyqtgraph's 0.2 ... 0.8 of
    an empty plot), which come back with a detail."""
    w = shown(qtbot, LatentForces(), 460, 430)
    plots = (w.norm_plot, w.dim_plot)

    def values_shown() -> list:
        return [p.getAxis(side).style["showValues"] for p in plots for side in ("left", "bottom")]

    for p in plots:
        assert p.getPlotItem().titleLabel.text.endswith(": none")
        assert "Inspect this frame" in p.toolTip()
    assert not any(values_shown())
    w.set_detail(None, "ik has no latent space: latent debugging needs DragPoser")
    assert all("ik has no latent space" in p.toolTip() for p in plots)
    assert "ik has no latent space" in w.info.text()
    w.set_detail(_detail())
    assert all(values_shown())
    assert not any(p.getPlotItem().titleLabel.text.endswith(": none") for p in plots)
    w.set_detail(None)
    assert not any(values_shown()) and "Inspect this frame" in w.norm_plot.toolTip()


def test_the_gallery_explains_its_colours(qtbot):
    w = shown(qtbot, LatentGallery(), 500, 400)
    assert w.legend.isVisible()
    text = w.legend.text()
    for colour in ("#4da3ff", "#8a93a6", "#ff8a1f", "#ff3b30", "#ffd60a"):
        assert colour in text
    assert "-2 sigma" in text and "+2 sigma" in text


@pytest.mark.parametrize("size", [(500, 400), (900, 700)])
def test_every_cell_label_of_the_gallery_is_inside_its_view(qtbot, size):
    w = shown(qtbot, LatentGallery(), *size)
    w.set_detail(_detail())
    for _ in range(3):
        QApplication.processEvents()
    view = w.plot.getPlotItem().getViewBox().sceneBoundingRect()
    cut = [t.textItem.toPlainText().split()[0] for t in w.labels if not view.contains(t.sceneBoundingRect())]
    assert not cut, f"labels cut off at the view's edge: {cut}"
    top = max(float(np.nanmax(line.getData()[1])) for line in w.lines)
    assert w.plot.getPlotItem().getViewBox().viewRange()[1][1] >= top, "the top row's heads are in the view"


def test_the_empty_gallery_says_how_to_fill_it_and_the_hint_goes_while_it_draws(qtbot):
    w = shown(qtbot, LatentGallery(), 500, 400)
    hint = [
        c for c in w.findChildren(QLabel) if c is not w.legend and c.isVisible() and "Inspect this frame" in c.text()
    ]
    assert hint, "an empty gallery says what fills it"
    w.set_detail(_detail())
    assert not hint[0].isVisible()
    w.set_detail(None)
    assert hint[0].isVisible()


def test_the_store_shared_with_the_map_still_marks_and_enables_the_jump(qtbot):
    """The window hands each snapshot to the map first: it reads the new solves into the
    shared store, and the readouts must still announce the flagged frames."""
    map_ = shown(qtbot, LatentMapPlot(), 300, 300)
    w = shown(qtbot, LatentReadouts(solved=map_.solved), 420, 250)
    marks = []
    w.flagsChanged.connect(marks.append)
    snap = _snap(n=20, flagged=(7,), frame=3)
    map_.update_snapshot(snap)
    w.update_snapshot(snap)
    assert marks == [[7]] and w.next_button.isEnabled()
    qtbot.mouseClick(w.next_button, Qt.MouseButton.LeftButton)


def test_the_forces_readout_counts_the_solvers_iterations(qtbot):
    """Seen under Xvfb: "11 iterations" for a solve of 10 (the status bar's "10 it"): the
    forces are taken at the start and after each step, one more than the steps."""
    w = shown(qtbot, LatentForces({}), 420, 400)
    w.set_detail(_detail())  # forces at 3 points of the path: 2 iterations
    assert "frame 7, 2 iterations" in w.info.text()
    assert w.iteration.maximum() == 2  # iteration 0 is the start


def test_no_stray_a_and_b_on_a_fresh_map(latent_map):
    """An "A" and a "B" sat on the map's origin until the Latent panel stored a latent."""
    assert [t.textItem.toPlainText() for t in latent_map.blend_labels] == ["", ""]
    latent_map.set_blend(np.array([0.0, 1.0]), np.array([2.0, -1.0]))
    assert [t.textItem.toPlainText() for t in latent_map.blend_labels] == ["A", "B"]
