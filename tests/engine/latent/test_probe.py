"""Per-frame probes of a real DragPoser run, and methods without a latent."""

from __future__ import annotations

import numpy as np
import pytest

from engine.latent.probe import NO_LATENT, LatentProbe, SolvesInLatent
from engine.latent.readouts import NearestLatents, bank_latents


def test_probe_of_a_dragposer_frame(dragposer_run):
    method, results = dragposer_run
    probe = LatentProbe.shipped()
    assert isinstance(method, SolvesInLatent)
    p = probe.after_step(method, 5, results[-1].latent)
    rec = method.last_solve
    assert p.start in ("predictor", "pose bank", "previous frame")
    assert p.path_xy.shape == (len(rec.solution.losses), 2)
    assert p.path_xy[-1] == pytest.approx(p.xy, abs=1e-5)  # the path ends at the solution
    d, _ = NearestLatents(bank_latents()).query(results[-1].latent)
    assert p.nearest == pytest.approx(float(d))
    assert p.norm == pytest.approx(np.linalg.norm(results[-1].latent))
    prior = rec.context.prediction.numpy()
    assert p.predictor == pytest.approx(np.linalg.norm(prior - results[-1].latent), rel=1e-5)
    assert p.flagged == (p.nearest > probe.map.nn_threshold or p.norm > probe.map.norm_threshold)


def test_an_older_frame_gets_no_record(dragposer_run):
    method, results = dragposer_run
    p = LatentProbe.shipped().after_step(method, 0, results[0].latent)
    assert p.start == "" and p.path_xy is None and np.isnan(p.predictor)


def test_methods_without_a_latent():
    from engine.methods import get_method

    ik = get_method("ik")
    assert not isinstance(ik, SolvesInLatent)
    assert LatentProbe.shipped().after_step(ik, 0, None) is None
    assert "ik has no latent space" in NO_LATENT.format(method="ik")


class _Term:
    def __init__(self, name, weight, enabled=True, active=1.0):
        self.name, self.weight, self.enabled, self._active = name, weight, enabled, active

    def activity(self, frame):
        return self._active


def test_record_keeps_the_frame_weights_and_names_the_start():
    from engine.methods.solve_record import record_of
    from engine.solver.frame import FrameContext

    terms = [_Term("a", 2.0, active=0.5), _Term("off", 1.0, enabled=False), _Term("zero", 0.0), _Term("b", 1.0)]
    ctx = FrameContext(None, frame=3)
    rec = record_of("sol", ctx, terms, predicted=True, bank=False)
    assert [(c.name, w) for c, w in rec.terms] == [("a", 1.0), ("b", 1.0)]
    terms[0].weight = 10.0  # a later frame's weights do not change this record
    assert rec.terms[0][1] == 1.0
    assert rec.start == "predictor"
    assert record_of("sol", ctx, terms, predicted=True, bank=True).start == "pose bank"
    assert record_of("sol", ctx, terms, predicted=False, bank=False).start == "previous frame"
    assert record_of("sol", FrameContext(None, frame=0), terms, False, False).start == "zero latent"
    # after a seek: the method reset (nothing solved since), or the frame solved before it
    assert record_of("sol", ctx, terms, False, False, previous=None).start == "zero latent"
    assert record_of("sol", ctx, terms, False, False, previous=0).start == "solved frame 0"
