"""app/schema.py: the optimizer panel is offered exactly the engine's choices."""

from __future__ import annotations

from app.schema import optimizer_choices
from engine import solver


def test_optimizer_choices_are_the_engines_including_the_prior_source():
    choices, defaults = optimizer_choices()
    assert choices["prior"] == solver.PRIORS == ("predictor", "trackers")
    assert choices["optimizer"] == tuple(solver.OPTIMIZERS) and choices["mode"] == tuple(solver.MODES)
    assert defaults["prior"] == "predictor" and defaults["tracker_prior_weight"] == 1.0
