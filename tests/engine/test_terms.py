"""Every constraint kind's one residual, checked on the inputs the kind declares
(``examples()``): a kind added to the registry is checked here without editing a list.

* its Jacobian-derived gradients equal autograd of the torch residual;
* its numpy and torch residuals give the same losses;
* ``A`` frames at once give what each frame gives alone;
* building, evaluating and checking a term never writes to the constraint.
"""

from __future__ import annotations

import copy

import numpy as np
import pytest
import torch

from engine import skeleton as sk
from engine.constraints import REGISTRY
from engine.constraints.base import state_arrays
from engine.constraints.residual import NUMPY, FrameInputs, FrameRows, torch_kit
from engine.constraints.term_stack import TermStack
from engine.kinematics import quaternion as Q
from engine.kinematics.fk import fk_matrices
from engine.kinematics.pose_state import PoseState

STAND = np.array([0.0, 0.0, 0.95])
L = 24


def random_pose(seed: int) -> tuple[np.ndarray, np.ndarray]:
    """Positions ``(22, 3)`` and world rotations ``(22, 3, 3)`` of a random pose standing
    at :data:`STAND`."""
    rng = np.random.default_rng(seed)
    local = np.tile([1.0, 0.0, 0.0, 0.0], (22, 1)) + rng.normal(0, 0.3, (22, 4))
    local /= np.linalg.norm(local, axis=-1, keepdims=True)
    pos, mats = fk_matrices(
        Q.to_matrix(torch.as_tensor(local)), torch.as_tensor(STAND), torch.as_tensor(sk.REST_OFFSETS)
    )
    return pos.numpy(), mats.numpy()


def _examples() -> list:
    pos, _ = random_pose(0)
    out = []
    for kind in sorted(REGISTRY):
        for i, _ in enumerate(REGISTRY[kind].examples(pos)):
            out.append(pytest.param(kind, i, id=f"{kind}-{i}"))
    return out


EXAMPLES = _examples()


def _inputs(seed: int) -> tuple[np.ndarray, np.ndarray, np.ndarray, FrameInputs]:
    pos, mats = random_pose(seed)
    rng = np.random.default_rng(seed + 10)
    prev = pos + rng.normal(0, 0.02, pos.shape)
    z = rng.normal(0, 1, L)
    return pos, mats, z, FrameInputs(prev, 3, rng.normal(0, 1, L))


def term_gradients(term, res, weights: np.ndarray, rows: np.ndarray | None = None) -> tuple[np.ndarray, ...]:
    """The position, turn and latent gradients ``(A, 22, 3)``, ``(A, 22, 3)``, ``(A, L)`` of
    one term's weighted losses (``weights (A, n)``): the term alone as a :class:`TermStack`."""
    stack = TermStack([term])
    return stack.gradients([res], stack.stack([res]), weights, L, rows)


def _example(kind: str, index: int):
    return REGISTRY[kind].examples(random_pose(0)[0])[index]


def test_every_kind_declares_examples_and_one_is_active():
    pos, mats, z, frame = _inputs(1)
    for kind, cls in REGISTRY.items():
        examples = cls.examples(random_pose(0)[0])
        assert examples, kind
        assert all(isinstance(c, cls) for c in examples)
        term = cls.terms(examples, frame)
        values = np.concatenate([t.losses(t.residual(NUMPY, pos[None], mats[None], z[None]))[0] for t in term])
        assert (values > 1e-8).any(), f"{kind}: no example has a loss at the test pose"


@pytest.mark.parametrize("seed", [1, 2])
@pytest.mark.parametrize("kind, index", EXAMPLES)
def test_gradients_from_the_jacobian_equal_autograd(kind, index, seed):
    """Loss, position gradient and rotation gradient of the term against autograd of the
    same residual on tensors (positions and rotation matrices as free variables; for a
    turn ``W -> exp([a]x) W`` the change is ``-axial(W G^T) . a`` with ``G = dL/dW``)."""
    pos, mats, z, frame = _inputs(seed)
    c = _example(kind, index)
    (term,) = type(c).terms([c], frame)
    P = torch.tensor(pos[None], requires_grad=True)
    W = torch.tensor(mats[None], requires_grad=True)
    Z = torch.tensor(z[None], requires_grad=True)
    kit = torch_kit()
    loss = term.losses(term.residual(kit, P, W, Z), kit)[0]
    weights = np.arange(1.0, len(loss) + 1.0)
    g_p, g_w, g_z = torch.autograd.grad((torch.as_tensor(weights) * loss).sum(), (P, W, Z), allow_unused=True)
    zeros = lambda like: np.zeros_like(like)  # noqa: E731
    g_p = zeros(pos) if g_p is None else g_p[0].numpy()
    g_w = zeros(mats) if g_w is None else g_w[0].numpy()
    g_z = zeros(z) if g_z is None else g_z[0].numpy()
    axial = lambda m: np.array([m[2, 1] - m[1, 2], m[0, 2] - m[2, 0], m[1, 0] - m[0, 1]])  # noqa: E731
    want_rot = -np.stack([axial(mats[j] @ g_w[j].T) for j in range(22)])

    res = term.residual(NUMPY, pos[None], mats[None], z[None], jac=True)
    np.testing.assert_allclose(term.losses(res)[0], loss.detach().numpy(), rtol=1e-10, atol=1e-14)
    got_pos, got_rot, got_z = term_gradients(term, res, weights[None])
    np.testing.assert_allclose(got_pos[0], g_p, rtol=1e-9, atol=1e-11)
    np.testing.assert_allclose(got_rot[0], want_rot, rtol=1e-9, atol=1e-11)
    np.testing.assert_allclose(got_z[0], g_z, rtol=1e-9, atol=1e-11)


@pytest.mark.parametrize("kind, index", EXAMPLES)
def test_a_batch_of_frames_is_each_frame_alone(kind, index):
    """``A = 3`` frames in one call (per-frame parameters in rows where the term has them)
    give each frame's one-frame residual, Jacobian and stopping test."""
    c = _example(kind, index)
    frames = [_inputs(s) for s in (3, 4, 5)]
    alone = [type(c).terms([c], f[3])[0] for f in frames]
    batch = alone[0].rows(3) if isinstance(alone[0], FrameRows) else alone[0]
    if isinstance(batch, FrameRows):
        for row, t in enumerate(alone):
            batch.set_row(row, t)
    P, W, Z = (np.stack([f[k] for f in frames]) for k in range(3))
    together = batch.residual(NUMPY, P, W, Z, jac=True, rows=np.arange(3))
    ok = batch.satisfied(P, W, Z, rows=np.arange(3))
    for a, (t, f) in enumerate(zip(alone, frames)):
        one = t.residual(NUMPY, f[0][None], f[1][None], f[2][None], jac=True)
        np.testing.assert_allclose(together.r[a], one.r[0], rtol=1e-12, atol=1e-15)
        for name in ("d_pos", "d_rot", "d_latent", "d_pos_entry", "d_rot_entry"):
            x, y = getattr(together, name), getattr(one, name)
            assert (x is None) == (y is None), name
            if x is not None:
                np.testing.assert_allclose(x[a], y[0], rtol=1e-12, atol=1e-15)
        np.testing.assert_array_equal(ok[a], t.satisfied(f[0][None], f[1][None], f[2][None])[0])


@pytest.mark.parametrize("kind, index", EXAMPLES)
def test_solving_never_changes_a_constraint(kind, index):
    """The studio publishes its constraint objects to the engine thread without copies or
    a lock: a term, a loss or a check must not write to them."""
    pos, mats, z, frame = _inputs(6)
    c = _example(kind, index)
    before = copy.deepcopy(c.to_dict())
    state = PoseState(
        torch.as_tensor(pos),
        None,
        torch.zeros(22, 4, dtype=torch.float64),
        torch.as_tensor(z),
        torch.as_tensor(frame.previous_positions),
        3,
        torch.as_tensor(frame.prediction),
        torch.as_tensor(mats),
    )
    c.loss(state), c.satisfied(state), c.gizmo(pos)
    for t in type(c).terms([c], frame):
        res = t.residual(NUMPY, pos[None], mats[None], z[None], jac=True)
        term_gradients(t, res, np.ones((1, len(t.names))))
        t.satisfied(pos[None], mats[None], z[None])
    after = c.to_dict()
    assert before.keys() == after.keys()
    for k in before:
        assert np.array_equal(np.asarray(before[k], dtype=object), np.asarray(after[k], dtype=object)), k


@pytest.mark.parametrize("kind, index", EXAMPLES)
def test_the_stopping_test_reads_well_formed_groups_of_the_residual(kind, index):
    """``satisfied`` is derived from the residual (:meth:`Term.satisfied_by`): each check
    group lies inside one constraint's entries, groups are numbered ``0 .. G-1`` with a
    bound each, and reading the residual the objective kept gives what ``satisfied``
    computes afresh."""
    pos, mats, z, frame = _inputs(8)
    c = _example(kind, index)
    for t in type(c).terms([c], frame):
        res = t.residual(NUMPY, pos[None], mats[None], z[None], jac=True)
        assert np.array_equal(t.satisfied_by(res), t.satisfied(pos[None], mats[None], z[None]))
        if t.check_group is None:
            continue
        group = np.asarray(t.check_group)
        assert group.shape == t.owner.shape and group.dtype.kind == "i"
        used = np.unique(group[group >= 0])
        assert np.array_equal(used, np.arange(len(used))), "groups numbered 0 .. G-1"
        assert np.shape(t.check_limits(slice(0, 1)))[-1] == len(used)
        for g in used:
            assert len(set(t.owner[group == g])) == 1, f"group {g} spans constraints"


def test_the_constraint_loss_is_the_term_on_the_state():
    """``Constraint.loss(state)`` (the autograd reference) is the term's squared norm on
    the state's arrays, and ``satisfied`` its stopping test."""
    pos, mats, z, frame = _inputs(7)
    for cls in REGISTRY.values():
        for c in cls.examples(random_pose(0)[0]):
            state = PoseState(
                torch.as_tensor(pos),
                None,
                torch.zeros(22, 4, dtype=torch.float64),
                torch.as_tensor(z),
                torch.as_tensor(frame.previous_positions),
                3,
                torch.as_tensor(frame.prediction),
                torch.as_tensor(mats),
            )
            (t,) = cls.terms([c], frame)
            P, W, Z = (a.numpy() for a in state_arrays(state))
            assert float(c.loss(state)) == pytest.approx(float(t.losses(t.residual(NUMPY, P, W, Z))[0, 0]), rel=1e-12)
            assert c.satisfied(state) == bool(t.satisfied(P, W, Z)[0, 0])


def test_the_kinds_table_of_the_optimizer_guide_is_the_generated_one():
    from pathlib import Path

    from engine.studio.kinds_table import BEGIN, END, kinds_table

    text = (Path(__file__).resolve().parents[2] / "docs" / "optimizer.md").read_text(encoding="utf-8")
    assert BEGIN in text and END in text, "docs/optimizer.md lost its kinds-table markers"
    table = text.split(BEGIN, 1)[1].split(END, 1)[0]
    assert table == kinds_table(), "run: PYTHONPATH=. python scripts/settings_table.py"
    for kind in REGISTRY:
        assert f"| `{kind}` |" in table
