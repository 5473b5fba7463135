"""app/schema.py: the optimizer panel is offered exactly the engine's settings, choices and ranges."""

from __future__ import annotations

import dataclasses

import pytest

from app.schema import optimizer_fields
from engine import solver
from engine.solver.settings import SETTINGS, OptimizerSettings
from engine.validation import Choice, Flag, Num


def test_optimizer_fields_are_the_engines_including_the_prior_source():
    fields = {f.name: f for f in optimizer_fields()}
    assert fields["prior"].choices == solver.PRIORS == ("predictor", "trackers")
    assert fields["optimizer"].choices == tuple(solver.OPTIMIZERS) and fields["mode"].choices == tuple(solver.MODES)
    assert fields["prior"].default == "predictor" and fields["tracker_prior_weight"].default == 1.0
    assert fields["root_anchor"].choices == ("upperneck", "none")  # offered; any joint is accepted
    defaults = OptimizerSettings()
    assert all(f.default == getattr(defaults, f.name) for f in fields.values())


def test_the_panels_ranges_are_the_validations(qtbot):
    from widgets.optimizer_panel import DECIMALS, OptimizerPanel

    fields = optimizer_fields()
    panel = OptimizerPanel(["ik"], fields)
    qtbot.addWidget(panel)
    assert list(panel.editors) == [f.name for f in fields] and len(fields) >= 10
    for f in fields:
        spec, w = SETTINGS[f.name], panel.editors[f.name]
        if isinstance(spec, Choice):
            assert set(w.itemText(i) for i in range(w.count())) <= set(spec.options), f.name
            continue
        if isinstance(spec, Flag):  # a check box: it shows the session's value and sends a toggle
            panel.set_state("ik", (), {f.name: True})
            assert w.isChecked(), f.name
            with qtbot.waitSignal(panel.settingChanged) as sent:
                w.setChecked(False)
            assert sent.args == [f.name, False]
            continue
        assert isinstance(spec, Num)
        smallest = (1 if spec.integer else 10.0**-DECIMALS) if spec.open_lo else 0
        assert w.minimum() == pytest.approx(spec.lo + smallest), f.name
        assert w.maximum() == pytest.approx(spec.hi), f.name
        spec.check(w.minimum())  # the panel's ends are values the engine accepts
        spec.check(w.maximum())


def test_every_panel_field_is_an_engine_field():
    names = {f.name for f in dataclasses.fields(OptimizerSettings)}
    assert {f.name for f in optimizer_fields()} <= names
