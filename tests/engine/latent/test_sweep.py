"""Dimension sweep and joint influence on a real DragPoser frame."""

from __future__ import annotations

import numpy as np
import pytest
import torch

from engine import skeleton as sk
from engine.latent.projection import default_map
from engine.latent.sweep import dimension_sweep, joint_influence, most_influential


def _decode(method, ctx, z):
    with torch.no_grad():
        return method.optimizer.decode(torch.tensor(z, dtype=torch.float32), ctx).positions.double().numpy()


def test_sweep_decodes_each_dimension_at_minus_zero_plus(dragposer_run):
    method, results = dragposer_run
    rec = method.last_solve
    z = results[-1].latent
    sigma = default_map().sigma
    s = dimension_sweep(method.optimizer, rec.context, z, sigma)
    assert s.poses.shape == (24, 3, sk.NUM_JOINTS, 3)
    assert s.poses[5, 1] == pytest.approx(_decode(method, rec.context, z), abs=1e-5)
    plus = z.copy()
    plus[5] += 2 * sigma[5]
    assert s.poses[5, 2] == pytest.approx(_decode(method, rec.context, plus), abs=1e-5)
    rel = s.poses[5] - s.poses[5, :, :1]
    assert s.motion[5] == pytest.approx(np.linalg.norm(rel - rel[1], axis=-1).max(0))
    assert s.motion.max() > 0.05  # two sigmas of some dimension move some joint by 5 cm or more
    assert len(s.top_joints(5, 3)) == 3 and s.top_joints(5, 1)[0] == sk.JOINT_NAMES[int(np.argmax(s.motion[5]))]


def test_joint_influence_matches_finite_differences(dragposer_run):
    method, results = dragposer_run
    rec = method.last_solve
    z = results[-1].latent.astype(np.float64)
    inf = joint_influence(method.optimizer, rec.context, z, "lwrist")
    j, h = sk.JOINT_INDEX["lwrist"], 1e-3  # the decoder bends: small steps
    for d in most_influential(inf, 2):
        e = np.zeros(24)
        e[d] = h
        fd = (_decode(method, rec.context, z + e)[j] - _decode(method, rec.context, z - e)[j]) / (2 * h)
        assert np.linalg.norm(fd) == pytest.approx(inf[d], rel=0.02)
    assert most_influential(inf, 3) == list(np.argsort(inf)[::-1][:3])
    with pytest.raises(KeyError):
        joint_influence(method.optimizer, rec.context, z, "tail")


def test_a_cancelled_sweep_and_forces_stop_between_steps(dragposer_run):
    from engine.latent.forces import record_forces
    from engine.progress import Cancelled

    method, results = dragposer_run
    rec = method.last_solve
    asked = []

    def after(n):
        def cancelled():
            asked.append(1)
            return len(asked) > n

        return cancelled

    with pytest.raises(Cancelled):
        dimension_sweep(method.optimizer, rec.context, results[-1].latent, default_map().sigma, cancelled=after(3))
    assert len(asked) == 4  # asked before each dimension, stopped at the fourth
    asked.clear()
    with pytest.raises(Cancelled):
        record_forces(method.optimizer, rec, default_map(), after(2))
    assert len(asked) == 3
