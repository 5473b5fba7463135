"""A frame's terms summed as one :class:`~engine.constraints.term_stack.TermStack`
(what the solver's numpy objective evaluates) give what each term gives alone: the same
losses, and gradients that are the sum of each term's. Every kind's examples are stacked
together, so a kind added to the registry is checked here without editing a list.
"""

from __future__ import annotations

import numpy as np
import pytest

from engine import skeleton as sk
from engine.constraints import REGISTRY
from engine.constraints.residual import NUMPY, FrameRows
from engine.constraints.term_stack import TermStack
from engine.kinematics.fk import levels
from tests.engine.test_terms import L, _inputs, random_pose, term_gradients


def _all_terms(frame) -> list:
    """Every kind's example terms, kind by kind (as ``build_terms`` groups them)."""
    pos = random_pose(0)[0]
    return [t for kind in sorted(REGISTRY) for t in REGISTRY[kind].terms(REGISTRY[kind].examples(pos), frame)]


@pytest.mark.parametrize("level_order", [False, True])
def test_the_stack_is_the_sum_of_its_terms(level_order):
    pos, mats, z, frame = _inputs(21)
    terms = _all_terms(frame)
    stack = TermStack(terms)
    res = [t.residual(NUMPY, pos[None], mats[None], z[None], jac=True) for t in terms]
    r = stack.stack(res)
    want = np.concatenate([t.losses(one) for t, one in zip(terms, res)], axis=1)
    np.testing.assert_allclose(stack.losses(r), want, rtol=1e-12, atol=1e-15)

    rows = levels(sk.PARENTS).unorder if level_order else None
    weights = np.linspace(0.5, 3.0, len(stack.names))[None]
    g_pos, g_rot, g_z = stack.gradients(res, r, weights, L, rows)
    want_pos, want_rot, want_z = np.zeros((1, 22, 3)), np.zeros((1, 22, 3)), np.zeros((1, L))
    at = 0
    for t, one in zip(terms, res):
        pos, rot, z = term_gradients(t, one, weights[:, at : at + len(t.names)], rows)
        want_pos, want_rot, want_z = want_pos + pos, want_rot + rot, want_z + z
        at += len(t.names)
    np.testing.assert_allclose(g_pos, want_pos, rtol=1e-12, atol=1e-13)
    np.testing.assert_allclose(g_rot, want_rot, rtol=1e-12, atol=1e-13)
    np.testing.assert_allclose(g_z, want_z, rtol=1e-12, atol=1e-13)


def test_rows_of_frames_are_each_frame_alone():
    """``A = 2`` frames with their own readings and weights: each row's losses and
    gradients are its frame's one-frame stack's."""
    inputs = [_inputs(s) for s in (22, 23)]
    alone = [_all_terms(f[3]) for f in inputs]
    batch = [t.rows(2) if isinstance(t, FrameRows) else t for t in alone[0]]
    for t, *frames in zip(batch, *alone):
        if isinstance(t, FrameRows):
            for row, f in enumerate(frames):
                t.set_row(row, f)
    P, W, Z = (np.stack([f[k] for f in inputs]) for k in range(3))
    stack = TermStack(batch)
    res = [t.residual(NUMPY, P, W, Z, jac=True, rows=np.arange(2)) for t in batch]
    r = stack.stack(res)
    weights = np.stack([np.linspace(0.5, 3.0, len(stack.names)), np.linspace(2.0, 1.0, len(stack.names))])
    losses, grads = stack.losses(r), stack.gradients(res, r, weights, L)
    for a, (terms, f) in enumerate(zip(alone, inputs)):
        one_stack = TermStack(terms)
        one = [t.residual(NUMPY, f[0][None], f[1][None], f[2][None], jac=True) for t in terms]
        one_r = one_stack.stack(one)
        np.testing.assert_allclose(losses[a], one_stack.losses(one_r)[0], rtol=1e-12, atol=1e-15)
        for got, want in zip(grads, one_stack.gradients(one, one_r, weights[a : a + 1], L)):
            np.testing.assert_allclose(got[a], want[0], rtol=1e-12, atol=1e-13)


def test_a_non_finite_entry_spoils_only_its_own_constraints_loss():
    """The solver leaves out a constraint whose loss is not finite: the stack's sums never
    mix two constraints' entries."""
    pos, mats, z, frame = _inputs(24)
    terms = _all_terms(frame)
    stack = TermStack(terms)
    r = stack.stack([t.residual(NUMPY, pos[None], mats[None], z[None]) for t in terms]).copy()
    spoilt = stack.owner[5]
    r[0, 5] = np.nan
    finite = np.isfinite(stack.losses(r)[0])
    assert not finite[spoilt]
    assert finite[np.arange(len(stack.names)) != spoilt].all()
