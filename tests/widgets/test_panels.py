"""Panels and plots (no VTK): edits become signals, state shown without echoing back."""

from __future__ import annotations

import numpy as np
import pytest
from PyQt6.QtCore import QPointF, Qt
from PyQt6.QtWidgets import QApplication

from engine.sensors import Sensor
from widgets.constraint_panel import ConstraintPanel
from widgets.latent_inspector import LatentInspector
from widgets.plots import LossPlots
from widgets.sensor_panel import SensorPanel
from widgets.timeline import Timeline


def test_timeline_scrub_emits_and_engine_frames_do_not(qtbot):
    t = Timeline()
    qtbot.addWidget(t)
    t.set_range(120)
    seen = []
    t.seekRequested.connect(seen.append)
    t.set_frame(30)
    assert seen == [] and t.slider.value() == 30
    with qtbot.waitSignal(t.seekRequested) as sig:
        t.slider.setValue(80)
    assert sig.args == [80] and t.counter.text().startswith("80 / 119")


def test_the_counter_never_shows_a_frame_past_the_range(qtbot):
    from widgets.timeline import Timeline

    t = Timeline()
    qtbot.addWidget(t)
    t.set_range(1556, 60.0)
    t.set_frame(1557)  # a live stream ahead of the range last given
    assert t.counter.text().startswith("1555 / 1555")


def test_sensor_panel_toggle_and_dof(qtbot):
    p = SensorPanel({"two": ("root", "lwrist")})
    qtbot.addWidget(p)
    p.set_sensors("two", {"root": Sensor("root"), "lwrist": Sensor("lwrist", dof=3)})
    assert p.rows["lwrist"]["dof"].currentText() == "3-DoF"
    with qtbot.waitSignal(p.sensorChanged) as sig:
        p.rows["root"]["enabled"].setChecked(False)
    assert sig.args == ["root", {"enabled": False}]
    with qtbot.waitSignal(p.failureRequested) as sig:
        p.rows["lwrist"]["fail"].click()
    assert sig.args == ["lwrist", 60]


SCHEMA = {
    "pin": [("joint", "joint", "lwrist"), ("target", "vec3", np.zeros(3)), ("radius", "float", 0.1)],
    "floor": [("margin", "float", 0.0)],
}


def test_an_empty_constraint_panel_says_how_to_add_one_and_the_hint_survives_editors(qtbot):
    p = ConstraintPanel(SCHEMA, empty_hint="Press Add.")
    qtbot.addWidget(p)
    p.show()
    assert p.scroll.widget() is p.hint and p.hint.isVisible() and p.hint.text() == "Press Add."
    assert not p.remove_button.isEnabled()  # nothing to remove
    pin = {"kind": "pin", "name": "pin1", "weight": 1.0, "enabled": True, "joint": "lwrist"}
    pin |= {"target": [0.0, 0.0, 1.0], "radius": 0.1}
    p.set_constraints([pin])
    assert p.scroll.widget() is p.editor and not p.hint.isVisible() and p.remove_button.isEnabled()
    p.list.setCurrentRow(-1)
    assert p.scroll.widget() is p.hint and p.hint.isVisible() and "Select a constraint" in p.hint.text()
    p.list.setCurrentRow(0)
    p.set_constraints([])  # the editor's widget replaced the hint, which was kept, not deleted
    assert p.scroll.widget() is p.hint and p.hint.isVisible() and p.hint.text() == "Press Add."
    assert not p.remove_button.isEnabled()
    assert [w for w in QApplication.topLevelWidgets() if w is p.hint] == []


def test_constraint_panel_builds_editors_from_the_schema(qtbot):
    p = ConstraintPanel(SCHEMA)
    qtbot.addWidget(p)
    with qtbot.waitSignal(p.addRequested) as sig:
        p.kinds.setCurrentText("pin")
        p.add_button.click()
    assert sig.args == ["pin"]
    p.set_constraints(
        [
            {
                "kind": "pin",
                "name": "pin1",
                "weight": 1.0,
                "enabled": True,
                "joint": "lwrist",
                "target": [0.0, 0.0, 1.0],
                "radius": 0.1,
            }
        ]
    )
    editor = p.editor
    assert editor is not None and editor.inputs["joint"].currentText() == "lwrist"
    with qtbot.waitSignal(p.changed) as sig:
        editor.inputs["target"].spins[2].setValue(1.5)
    assert sig.args[0] == "pin1" and np.allclose(sig.args[1]["target"], [0, 0, 1.5])
    with qtbot.waitSignal(p.changed) as sig:
        p.list.item(0).setCheckState(Qt.CheckState.Unchecked)
    assert sig.args == ["pin1", {"enabled": False}]
    with qtbot.waitSignal(p.removeRequested) as sig:
        p.remove_button.click()
    assert sig.args == ["pin1"]


def _records(frames, losses=None):
    from tests.widgets.conftest import FakeRecord

    return tuple(FakeRecord(f, 2, 3.0 + f, dict(losses or {"total": 0.1, "pos:root": 0.05 * (f + 1)})) for f in frames)


def test_plots_draw_the_engines_history_and_restart_with_it(qtbot, fake_snapshot):
    p = LossPlots()
    qtbot.addWidget(p)
    for i in range(5):
        p.update_snapshot(fake_snapshot(seq=i + 1, frame=i, history=_records(range(i + 1))))
    total = p.iter_curves.items["total"]  # xData/yData: before the log-axis transform
    # the start latent's loss at 0, then one point per step: N iterations end at x = N
    assert list(total.xData) == [0, 1] and np.allclose(total.yData, [1.0, 0.1])
    root = p.history_curves.items["pos:root"]
    assert list(root.xData) == [0, 1, 2, 3, 4] and np.allclose(root.yData, [0.05, 0.1, 0.15, 0.2, 0.25])
    assert list(p.ms_curve.yData) == [3.0, 4.0, 5.0, 6.0, 7.0]
    p.update_snapshot(fake_snapshot(seq=9, frame=0, history=_records([0])))  # the engine looped
    assert list(p.history_curves.items["pos:root"].xData) == [0]


def test_frames_whose_snapshots_were_never_drawn_still_reach_the_history(qtbot, fake_snapshot):
    """The GUI draws only the newest snapshot; the engine's record fills the gaps."""
    p = LossPlots()
    qtbot.addWidget(p)
    p.update_snapshot(fake_snapshot(seq=1, frame=0, history=_records([0])))
    p.update_snapshot(fake_snapshot(seq=40, frame=39, history=_records(range(40))))
    assert len(p.history_curves.items["pos:root"].xData) == 40
    assert len(p.iter_curve.xData) == 40
    w = LatentInspector()
    qtbot.addWidget(w)
    from tests.widgets.conftest import FakeRecord

    # a solver slower than the clip solves every third frame: the strip's x is still frames
    recs = tuple(FakeRecord(3 * k, 1, 1.0, {}, np.full(24, k / 10)) for k in range(30))
    w.update_snapshot(fake_snapshot(seq=2, frame=87, latent=recs[-1].latent, history=recs))
    image = w.strip.image
    assert image.shape == (30, 24) and image[0, 0] == 0.0 and image[-1, 0] == pytest.approx(2.9)
    left, right = w.strip.mapToParent(QPointF(0, 0)).x(), w.strip.mapToParent(QPointF(30, 0)).x()
    assert left == pytest.approx(0.0) and right == pytest.approx(87.0)


@pytest.mark.parametrize("can_decode", [False, True])
def test_latent_debugger_needs_a_decoder(qtbot, fake_snapshot, can_decode):
    w = LatentInspector()
    qtbot.addWidget(w)
    w.update_snapshot(fake_snapshot(latent=np.linspace(-1, 1, 24), can_decode=can_decode))
    assert w.debug_box.isEnabled() == can_decode
    assert ("decoder" in w.debug_box.toolTip()) != can_decode
    if can_decode:
        w.debug.setChecked(True)
        with qtbot.waitSignal(w.decodeRequested) as sig:
            w.value.setValue(250)
        assert sig.args[0][0] == pytest.approx(2.5)


def _fields():
    from widgets.optimizer_panel import SettingField

    return (
        SettingField("mode", "Mode", "choice", "realtime", choices=("realtime", "offline")),
        SettingField("iterations", "Iterations", "int", 10, lo=1, hi=10_000),
        SettingField("optimizer", "Update", "choice", "auto", choices=("sgd", "adam", "adam-carry")),
        SettingField("lr", "Learning rate", "float", 0.05, lo=0, hi=10, open_lo=True, step=0.005),
        SettingField("prior", "Prior", "choice", "predictor", choices=("predictor", "trackers")),
        SettingField("root_anchor", "Anchor", "choice", "upperneck", choices=("upperneck", "none")),
        SettingField("sensor_blend", "Blend", "float", 0.0, lo=0, hi=1e6, step=0.1, unit="s"),
        SettingField("reach", "Reach", "bool", True),
    )


def test_optimizer_panel_offers_the_engine_choices_and_emits_edits(qtbot):
    from widgets.optimizer_panel import OptimizerPanel

    p = OptimizerPanel(["ik", "dragposer"], _fields())
    qtbot.addWidget(p)
    opt, anchor = p.editors["optimizer"], p.editors["root_anchor"]
    assert [opt.itemText(i) for i in range(opt.count())] == ["sgd", "adam", "adam-carry"]
    seen = []
    p.settingChanged.connect(lambda n, v: seen.append((n, v)))
    p.set_state("dragposer", (), {"optimizer": "adam", "root_anchor": "lwrist", "iterations": 7, "reach": False})
    assert seen == [] and opt.currentText() == "adam" and p.editors["iterations"].value() == 7
    assert anchor.currentText() == "lwrist"  # a joint from a scene file is shown, not dropped
    assert not p.editors["reach"].isChecked()
    opt.setCurrentText("adam-carry")
    anchor.setCurrentText("none")
    p.editors["lr"].setValue(0.2)
    p.editors["prior"].setCurrentText("trackers")
    p.editors["reach"].setChecked(True)
    assert seen == [
        ("optimizer", "adam-carry"),
        ("root_anchor", "none"),
        ("lr", pytest.approx(0.2)),
        ("prior", "trackers"),
        ("reach", True),
    ]


def test_optimizer_panel_shows_the_given_fields_with_their_ranges_and_units(qtbot):
    from widgets.optimizer_panel import OptimizerPanel, SettingField

    fields = (*_fields(), SettingField("heading", "Heading", "choice", "anchor"))  # no values: no control
    p = OptimizerPanel(["ik"], fields)
    qtbot.addWidget(p)
    assert list(p.editors) == [f.name for f in _fields()]
    lr, blend = p.editors["lr"], p.editors["sensor_blend"]
    assert lr.minimum() == pytest.approx(1e-4) and lr.maximum() == 10  # (0, 10]: the smallest shown step above 0
    assert blend.suffix() == " s" and p.editors["iterations"].maximum() == 10_000
    assert OptimizerPanel(["ik"]).editors == {}


def test_unticking_a_legend_term_hides_it_in_every_plot_and_a_restart_keeps_it_hidden(qtbot, fake_snapshot):
    p = LossPlots()
    qtbot.addWidget(p)
    p.update_snapshot(fake_snapshot(seq=1, frame=5))
    item = p.legend.findItems("pos:root", Qt.MatchFlag.MatchExactly)[0]
    item.setCheckState(Qt.CheckState.Unchecked)
    assert not p.iter_curves.items["pos:root"].isVisible() and not p.history_curves.items["pos:root"].isVisible()
    assert p.iter_curves.items["total"].isVisible()
    p.clear()  # a new clip: the curves are rebuilt (a seek or loop keeps them)
    p.update_snapshot(fake_snapshot(seq=2, frame=0))
    assert not p.iter_curves.items["pos:root"].isVisible() and p.iter_curves.items["total"].isVisible()
    assert p.legend.findItems("pos:root", Qt.MatchFlag.MatchExactly)[0].checkState() == Qt.CheckState.Unchecked


@pytest.mark.parametrize("zero", [0.0, 3e-16])
def test_a_zero_loss_term_leaves_a_gap_instead_of_stretching_the_log_axis(qtbot, fake_snapshot, zero):
    """Exactly 0, and the float rounding of 0 that the hip sensor's term has while the hip
    tracker sets the root (drawn, it pulled the log axis down to 1e-16)."""
    p = LossPlots()
    qtbot.addWidget(p)
    p.show()
    losses = ({"total": 1.0, "pos:root": zero}, {"total": 0.1, "pos:root": zero})
    p.update_snapshot(fake_snapshot(losses=losses))
    p.grab()  # painting all-NaN curves on log axes must not warn (warnings are errors here)

    def drawn(curve) -> bool:
        return curve.yData is not None and bool(np.isfinite(np.asarray(curve.yData, float)).any())

    assert not drawn(p.iter_curves.items["pos:root"]) and not drawn(p.history_curves.items["pos:root"])
    assert p.iter_curves.items["total"].dataBounds(1)[0] == pytest.approx(-1.0)  # log10(0.1)
    assert p.legend.terms == ("total", "pos:root")  # the term stays in the legend


def test_empty_loss_plots_say_why_in_their_titles(qtbot, fake_snapshot):
    """IK meets its trackers exactly and does not iterate: its plots say so instead of
    looking broken; a method with losses gets the plain titles back."""
    from tests.widgets.conftest import FakeRecord

    p = LossPlots()
    qtbot.addWidget(p)
    zero = {"total": 0.0, "pos:root": 0.0}
    snap = fake_snapshot(seq=1, losses=(), method="ik", history=(FakeRecord(0, 0, 1.0, zero, None),))
    p.update_snapshot(snap)
    assert p.iteration_plot.getPlotItem().titleLabel.text == "Loss per iteration: none"
    assert "ik does not iterate" in p.iteration_plot.toolTip()
    p.update_snapshot(fake_snapshot(seq=2, losses=(), method="autoencoder", history=snap.history))
    assert "autoencoder does not iterate" in p.iteration_plot.toolTip()  # the same title, its own reason
    assert p.history_plot.getPlotItem().titleLabel.text == "Loss history: all 0"
    # a method whose one reported iteration is all zeros (ik in the studio): said on both plots
    p.update_snapshot(fake_snapshot(seq=3, losses=(zero,), method="ik", history=snap.history))
    assert p.iteration_plot.getPlotItem().titleLabel.text == "Loss per iteration: all 0"
    assert "every term is 0" in p.iteration_plot.toolTip().lower()
    p.update_snapshot(fake_snapshot(seq=4))
    assert p.iteration_plot.getPlotItem().titleLabel.text == "Loss per iteration"
    assert p.history_plot.getPlotItem().titleLabel.text == "Loss history" and not p.history_plot.toolTip()


def _terms(joints):
    return {"total": 1.0, **{f"{k}:{j}": 0.1 for j in joints for k in ("pos", "rot")}, "temporal_prior": 0.01}


SIX = ("root", "upperneck", "lwrist", "rwrist", "lankle", "rankle")


def test_every_term_is_listed_beside_the_plots_without_covering_them(qtbot, fake_snapshot):
    """Six trackers make 14 terms; the in-plot legend showed 8 and covered the curves."""
    p = LossPlots()
    qtbot.addWidget(p)
    p.resize(1400, 300)  # the plots dock of a 1600 x 980 window
    p.show()
    qtbot.waitExposed(p)
    terms = _terms(SIX)
    p.update_snapshot(fake_snapshot(losses=(terms, terms)))
    assert p.legend.terms == tuple(terms) and p.legend.count() == 14
    assert p.iteration_plot.plotItem.legend is None  # nothing drawn over the curves
    for plot in (p.iteration_plot, p.history_plot):
        assert plot.geometry().right() < p.legend.geometry().left()
    # every entry can be reached (the list scrolls when it is taller than the dock)
    p.legend.scrollToItem(p.legend.item(13))
    assert p.legend.visualItemRect(p.legend.item(13)).bottom() <= p.legend.viewport().height()


def test_terms_of_removed_sensors_leave_the_legend_and_the_plots(qtbot, fake_snapshot):
    p = LossPlots()
    qtbot.addWidget(p)
    six = _terms(SIX)
    p.update_snapshot(fake_snapshot(seq=1, frame=3, losses=(six, six)))
    three = _terms(("upperneck", "lwrist", "rwrist"))  # the preset changed
    p.update_snapshot(fake_snapshot(seq=2, frame=4, losses=(three, three)))
    assert p.legend.terms == tuple(three)
    assert set(p.iter_curves.items) == set(three) and set(p.history_curves.items) == set(three)
    assert "pos:lankle" not in [p.legend.item(i).text() for i in range(p.legend.count())]


def test_frame_axes_show_frames_not_thousands(qtbot, fake_snapshot):
    """Past frame 1000 pyqtgraph rescaled the axis to read "frame (x0.001)"."""
    p = LossPlots()
    qtbot.addWidget(p)
    p.show()
    p.update_snapshot(fake_snapshot(seq=1, frame=2400, history=_records(range(2000, 2400))))
    p.grab()
    for plot in (p.cost_plot, p.history_plot):
        axis = plot.getAxis("bottom")
        assert axis.autoSIPrefixScale == 1.0 and "x0.001" not in axis.labelString()


def test_latent_history_strip_gives_each_dimension_room(qtbot, fake_snapshot):
    """The strip was about 20 px tall for 24 dimensions in the studio's latent dock."""
    w = LatentInspector()
    qtbot.addWidget(w)
    w.resize(430, 330)  # the latent dock of a 1600 x 980 window
    w.show()
    qtbot.waitExposed(w)
    w.update_snapshot(fake_snapshot(seq=2, latent=np.linspace(-1, 1, 24)))
    qtbot.waitUntil(lambda: w.strip_plot.isVisible())
    view = w.strip_plot.plotItem.vb.sceneBoundingRect()
    assert view.height() >= 24 * 4, f"strip view {view.height():.0f} px for 24 dimensions"


def _panel_in_window(qtbot, schema):
    """The panel in a dock-sized window, shown, as the studio has it."""
    p = ConstraintPanel(schema)
    qtbot.addWidget(p)
    p.resize(430, 420)
    p.show()
    qtbot.waitExposed(p)
    return p


def test_selecting_a_constraint_with_many_fields_does_not_grow_the_window(qtbot):
    """An end_effector or sensor editor made the dock, and so the window, taller than the screen."""
    from app.schema import constraint_schema

    schema = constraint_schema()
    p = _panel_in_window(qtbot, schema)
    empty = p.minimumSizeHint()
    for kind in ("end_effector", "look_at", "floor", "bounds"):
        values = {"kind": kind, "name": f"{kind}1", "weight": 1.0, "enabled": True}
        values.update({f[0]: f[2] for f in schema[kind]})
        p.set_constraints([values])
        assert p.editor is not None
        hint = p.minimumSizeHint()
        assert hint.height() <= empty.height() + 5, kind
        assert hint.width() <= max(empty.width(), 430), kind


def test_the_panel_offers_only_user_facing_kinds():
    """``sensor`` and ``temporal_prior`` are built by methods; offering them confused users."""
    from app.schema import constraint_schema

    kinds = set(constraint_schema())
    assert {"pin", "bounds", "look_at", "balance", "floor"} <= kinds
    assert not kinds & {"sensor", "temporal_prior"}


def test_choice_and_joint_list_fields_are_edited_with_pickers(qtbot):
    """Balance mode was free text and floor joints could not be edited at all."""
    from app.schema import constraint_schema

    schema = constraint_schema()
    p = _panel_in_window(qtbot, schema)
    p.set_constraints(
        [{"kind": "balance", "name": "b", "weight": 1.0, "enabled": True, "mode": "head_over_hip", "tolerance": 0.05}]
    )
    mode = p.editor.inputs["mode"]
    assert [mode.itemText(i) for i in range(mode.count())] == ["head_over_hip", "com_over_feet"]
    with qtbot.waitSignal(p.changed) as sig:
        mode.setCurrentText("com_over_feet")
    assert sig.args == ["b", {"mode": "com_over_feet"}]
    p.set_constraints(
        [
            {
                "kind": "floor",
                "name": "f",
                "weight": 1.0,
                "enabled": True,
                "joints": ["lankle", "rankle"],
                "floor_height": 0.0,
            }
        ]
    )
    joints = p.editor.inputs["joints"]
    assert joints.joints() == ("lankle", "rankle")
    with qtbot.waitSignal(p.changed) as sig:
        joints.actions_by_joint["ltoe"].setChecked(True)
    assert sig.args == ["f", {"joints": ("lankle", "ltoe", "rankle")}]


def test_the_editor_follows_edits_made_elsewhere_and_add_selects_the_new_constraint(qtbot):
    p = _panel_in_window(qtbot, SCHEMA)
    pin = {
        "kind": "pin",
        "name": "pin1",
        "weight": 1.0,
        "enabled": True,
        "joint": "lwrist",
        "target": [0.0, 0.0, 1.0],
        "radius": 0.1,
    }
    p.set_constraints([pin])
    seen = []
    p.changed.connect(lambda n, ch: seen.append((n, ch)))
    p.set_constraints([{**pin, "target": [0.5, 0.2, 1.0]}])  # a gizmo drag
    assert seen == []
    with qtbot.waitSignal(p.changed) as sig:  # the next edit keeps the drag's x and y
        p.editor.inputs["target"].spins[2].setValue(1.4)
    assert np.allclose(sig.args[1]["target"], [0.5, 0.2, 1.4])
    other = {"kind": "floor", "name": "floor1", "weight": 1.0, "enabled": True, "margin": 0.0}
    p.set_constraints([{**pin, "target": [0.5, 0.2, 1.4]}, other])  # Add: the new one is selected
    assert p.current_name() == "floor1" and "margin" in p.editor.inputs
    p.list.setCurrentRow(0)
    p.set_constraints([{**pin, "target": [0.5, 0.2, 1.4]}, other, {**other, "name": "floor2"}])
    assert p.current_name() == "floor2"


def test_store_as_b_after_a_seek_in_debug_mode_stores_the_new_frames_latent(qtbot, fake_snapshot):
    w = LatentInspector()
    qtbot.addWidget(w)
    a, b = np.linspace(-1, 1, 24), np.linspace(1, -1, 24)
    w.update_snapshot(fake_snapshot(seq=1, frame=5, latent=a, can_decode=True))
    w.debug.setChecked(True)
    w.capture_a.click()
    w.update_snapshot(fake_snapshot(seq=2, frame=40, latent=b, can_decode=True))  # a seek while debugging
    w.capture_b.click()
    assert np.allclose(w.stored["a"], a) and np.allclose(w.stored["b"], b)
    with qtbot.waitSignal(w.decodeRequested) as sig:
        w.mix.setValue(50)
    assert np.allclose(sig.args[0], 0.5 * (a + b))


def test_store_keeps_the_scrubbed_latent_so_a_to_b_blends_two_edits(qtbot, fake_snapshot):
    w = LatentInspector()
    qtbot.addWidget(w)
    z = np.linspace(-1, 1, 24)
    w.update_snapshot(fake_snapshot(seq=1, frame=5, latent=z, can_decode=True))
    w.debug.setChecked(True)
    w.dim.setValue(3)
    w.value.setValue(150)  # dimension 3 scrubbed to 1.5
    w.capture_a.click()
    w.value.setValue(-150)
    w.capture_b.click()
    assert w.stored["a"][3] == pytest.approx(1.5) and w.stored["b"][3] == pytest.approx(-1.5)
    assert np.allclose(np.delete(w.stored["a"], 3), np.delete(z, 3))
    with qtbot.waitSignal(w.decodeRequested) as sig:
        w.mix.setValue(25)
    assert sig.args[0][3] == pytest.approx(0.75)


def test_a_plot_update_that_changes_the_range_paints_once(qtbot, fake_snapshot, monkeypatch):
    """pyqtgraph fits an auto range in the paint, which then asked for a second paint of
    the whole plot (each 5-35 ms under software rendering): the update settles it first."""
    import pyqtgraph as pg

    paints = []
    paint = pg.GraphicsView.paintEvent
    monkeypatch.setattr(pg.GraphicsView, "paintEvent", lambda view, ev: (paints.append(view), paint(view, ev))[1])
    p = LossPlots()
    qtbot.addWidget(p)
    p.resize(900, 300)
    p.show()
    qtbot.waitExposed(p)
    p.update_snapshot(fake_snapshot(seq=1))
    qtbot.wait(100)
    for scale in (10.0, 1000.0):  # each update moves the log axis by decades
        paints.clear()
        losses = tuple({k: v * scale for k, v in d.items()} for d in fake_snapshot().losses)
        p.update_iterations(fake_snapshot(seq=2, losses=losses))
        qtbot.wait(150)
        assert paints.count(p.iteration_plot) == 1, f"{paints.count(p.iteration_plot)} paints for one update"


def test_all_zero_loss_plots_span_the_iterations_and_frames_with_whole_ticks(qtbot, fake_snapshot):
    """With ik, "Loss per iteration: all 0": the x axis spans the iterations run (whole
    numbers only, not pyqtgraph's 0.2 to 0.8 of an empty plot) and the history the frames
    solved; the y axis shows no values; a method with losses gets its auto range and
    values back."""
    from tests.widgets.conftest import FakeRecord

    p = LossPlots()
    qtbot.addWidget(p)
    p.resize(1200, 260)
    p.show()
    qtbot.waitExposed(p)
    zero = {"total": 0.0, "pos:root": 0.0}
    history = tuple(FakeRecord(f, 1, 1.0, zero) for f in range(20, 40))
    p.update_snapshot(fake_snapshot(seq=1, losses=(zero,), method="ik", history=history))
    p.grab()
    it, hist = p.iteration_plot.getPlotItem(), p.history_plot.getPlotItem()
    assert it.titleLabel.text == "Loss per iteration: all 0" and hist.titleLabel.text == "Loss history: all 0"
    assert it.getViewBox().viewRange()[0] == pytest.approx([-0.5, 0.5])
    assert hist.getViewBox().viewRange()[0] == pytest.approx([20.0, 39.0])
    axis = it.getAxis("bottom")
    ticks = [v for _s, values in axis.tickValues(-0.5, 0.5, axis.width()) for v in values]
    assert ticks == [0.0]  # the start, not -0.4, -0.2, 0.0...
    assert not it.getAxis("left").style["showValues"] and not hist.getAxis("left").style["showValues"]
    p.update_snapshot(fake_snapshot(seq=2))  # losses again
    assert it.getViewBox().autoRangeEnabled()[0] and it.getAxis("left").style["showValues"]
    assert hist.getAxis("left").style["showValues"]
