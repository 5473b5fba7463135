"""Term forces replayed along a real DragPoser solve (shipped models, bundled clip)."""

from __future__ import annotations

import numpy as np
import pytest
import torch

from engine.latent.forces import TermForces, record_forces, term_forces
from engine.latent.projection import default_map


def test_forces_replay_the_solve(dragposer_run):
    method, results = dragposer_run
    rec = method.last_solve
    sol = rec.solution
    assert sol.path is not None and len(sol.path) == len(sol.losses)
    f = record_forces(method.optimizer, rec, default_map())
    K, T = len(sol.path), len(rec.terms)
    assert f.forces.shape == (K, T, 24) and f.plane.shape == (K, T, 2)
    # the weighted term losses add up to the solver's own total at every iteration
    assert f.losses.sum(1) == pytest.approx([row["total"] for row in sol.losses], rel=1e-3, abs=1e-6)
    assert f.plane == pytest.approx(f.forces @ default_map().components.T)
    assert f.names == tuple(c.name for c, _ in rec.terms) and "sensor:lwrist" in f.names


def test_a_force_is_minus_the_terms_gradient_by_finite_differences(dragposer_run):
    method, _ = dragposer_run
    rec = method.last_solve
    z0 = np.asarray(rec.solution.path[0], np.float64)
    t = [c.name for c, _ in rec.terms].index("sensor:lwrist")
    c, w = rec.terms[t]
    f = term_forces(method.optimizer, rec.context, rec.terms, z0[None])
    direction = f.forces[0, t] / np.linalg.norm(f.forces[0, t])

    def loss(z):
        with torch.no_grad():
            return w * float(c.loss(method.optimizer.decode(torch.tensor(z, dtype=torch.float32), rec.context)))

    h = 1e-3  # the decoder bends: larger steps measure the curvature too
    slope = (loss(z0 + h * direction) - loss(z0 - h * direction)) / (2 * h)
    # along the force, the term's loss falls at the rate of the force's norm
    assert slope == pytest.approx(-np.linalg.norm(f.forces[0, t]), rel=0.02)


def test_conflicts_name_opposed_terms():
    forces = np.zeros((1, 3, 4))
    forces[0, 0] = [1, 0, 0, 0]
    forces[0, 1] = [-2, 0.1, 0, 0]
    forces[0, 2] = [0, 1, 0, 0]
    f = TermForces(("a", "b", "c"), np.ones(3), np.zeros((1, 3)), forces)
    got = f.conflicts()
    assert [(a, b) for a, b, _ in got] == [("a", "b")] and got[0][2] < -0.99
    assert f.norms[0] == pytest.approx([1, np.hypot(2, 0.1), 1])
    assert f.total[0] == pytest.approx([-1, 1.1, 0, 0])
