"""What the solver's fast path keeps between evaluations stays right: a term's
frame-constant Jacobian blocks (:meth:`Term.kept`), the rotation rows written in place, the
gradients accumulated in the chain's level order, and FK reading parents through slices.
Every kind is checked on the inputs its ``examples()`` declares (as ``test_terms.py``).
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from engine import skeleton as sk
from engine.constraints import SensorConstraint
from engine.constraints.residual import NUMPY
from engine.kinematics.fk import fk_level_order, levels
from tests.engine.test_terms import EXAMPLES, _example, _inputs, random_pose, term_gradients

_FIELDS = ("r", "d_pos", "d_rot", "d_latent", "d_pos_entry", "d_rot_entry")


@pytest.mark.parametrize("kind, index", EXAMPLES)
def test_a_term_evaluated_again_gives_what_a_fresh_term_gives(kind, index):
    """The second evaluation of a term (its kept blocks reused, its rotation rows
    rewritten) equals the first evaluation of a new term at the same pose; the first
    evaluation's values were at another pose, so stale rows would show."""
    c = _example(kind, index)
    pos, mats, z, frame = _inputs(11)
    pos2, mats2, z2, _ = _inputs(12)
    (used,) = type(c).terms([c], frame)
    used.residual(NUMPY, pos[None], mats[None], z[None], jac=True)
    again = used.residual(NUMPY, pos2[None], mats2[None], z2[None], jac=True)
    (fresh,) = type(c).terms([c], frame)
    want = fresh.residual(NUMPY, pos2[None], mats2[None], z2[None], jac=True)
    for name in _FIELDS:
        x, y = getattr(again, name), getattr(want, name)
        assert (x is None) == (y is None), name
        if x is not None:
            np.testing.assert_array_equal(x, y, err_msg=name)


def test_kept_blocks_are_forgotten_when_a_row_takes_new_readings():
    """A tracker term of two rows evaluated with both trackers connected, then given a
    lost reading in row 1 (``set_row``): its position Jacobian there is zero, as the
    reading says, not the connected one kept from before."""
    pos, mats, z, frame = _inputs(13)
    on = SensorConstraint(name="hand", joint="lwrist", dof=6, position=pos[sk.JOINT_NAMES.index("lwrist")] + 0.1)
    off = SensorConstraint(name="hand", joint="lwrist", dof=6, position=on.position, connected=False)
    (term,) = SensorConstraint.terms([on], frame)
    batch = term.rows(2)
    P, W, Z = (np.stack([a, a]) for a in (pos, mats, z))
    first = batch.residual(NUMPY, P, W, Z, jac=True)
    assert np.abs(first.d_pos_entry[1]).sum() > 0 and np.abs(first.d_rot_entry[1]).sum() > 0
    batch.set_row(1, SensorConstraint.terms([off], frame)[0])
    second = batch.residual(NUMPY, P, W, Z, jac=True)
    assert not second.d_pos_entry[1].any() and not second.d_rot_entry[1].any()
    np.testing.assert_array_equal(second.d_pos_entry[0], first.d_pos_entry[0])


@pytest.mark.parametrize("kind, index", EXAMPLES)
def test_gradients_accumulated_in_level_order_are_the_joint_order_ones_reordered(kind, index):
    """``gradients(..., rows=unorder)`` writes joint ``j``'s gradient to row
    ``unorder[j]``: the same numbers, to the bit, as joint order gathered into level order."""
    pos, mats, z, frame = _inputs(14)
    c = _example(kind, index)
    lv = levels(sk.PARENTS)
    for t in type(c).terms([c], frame):
        res = t.residual(NUMPY, pos[None], mats[None], z[None], jac=True)
        w = np.arange(1.0, len(t.names) + 1.0)[None]
        joint = term_gradients(t, res, w)
        level = term_gradients(t, res, w, lv.unorder)
        np.testing.assert_array_equal(level[0], joint[0][:, lv.order])
        np.testing.assert_array_equal(level[1], joint[1][:, lv.order])
        np.testing.assert_array_equal(level[2], joint[2])


def test_fk_through_parent_slices_is_fk_through_gathers():
    """Levels whose parents are consecutive rows or one row are read through slices:
    the same positions and rotations, to the bit, as gathering every level's parents."""
    lv = levels(sk.PARENTS)
    assert any(s is not None for s in lv.parent_slices)
    for rows, view in zip(lv.parent_rows, lv.parent_slices):
        if view is not None:
            assert np.array_equal(np.broadcast_to(np.arange(22)[view], rows.shape), rows)
    rng = np.random.default_rng(3)
    _, mats = random_pose(4)
    local = np.stack([mats[lv.order], random_pose(5)[1][lv.order]])  # (2, 22, 3, 3): any rotations
    root = rng.normal(0, 1, (2, 3))
    bones = np.asarray(sk.REST_OFFSETS, dtype=np.float64)[lv.order[1:], :, None]
    pos, world = fk_level_order(local, root, bones, lv)
    gathered = dataclasses.replace(lv, parent_slices=(None,) * len(lv.parent_rows))
    pos2, world2 = fk_level_order(local, root, bones, gathered)
    np.testing.assert_array_equal(pos, pos2)
    np.testing.assert_array_equal(world, world2)
