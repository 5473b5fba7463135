"""The rotation part of a tracker or end-effector term and its per-entry Jacobian.

:func:`rotation_residual` is ``scale * (W - T)`` for world rotations ``W`` and targets
``T``, with its Jacobian w.r.t. a world turn of each entry's joint; :func:`entry_block`
gives the per-entry block a term writes it into; :data:`EPS3` is the Levi-Civita symbol
both (and the solver's chain, :mod:`engine.solver.chain`) build cross products with.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from engine.constraints.residual import Kit

#: Levi-Civita symbol: ``(a x v)_i = EPS3[i, k, l] a_k v_l``.
EPS3 = np.zeros((3, 3, 3))
EPS3[0, 1, 2] = EPS3[1, 2, 0] = EPS3[2, 0, 1] = 1.0
EPS3[0, 2, 1] = EPS3[2, 1, 0] = EPS3[1, 0, 2] = -1.0


#: ``W.reshape(9) @ _TURN`` is ``d (W - T)_ij / d a_k = ([e_k]x W)_ij = EPS3[i, k, l] W_lj``
#: as ``(i, j, k)`` flattened: the per-entry Jacobian of a rotation residual.
_TURN = np.einsum("ikl,jm->lmijk", EPS3, np.eye(3)).reshape(9, 27)


def rotation_residual(
    kit: Kit, W: Any, T: Any, scale: Any, jac: bool, out: np.ndarray | None = None
) -> tuple[Any, np.ndarray | None]:
    """The rotation part of a tracker or end-effector term: ``scale (A, s) * (W - T)``,
    flattened to ``(A, s * 9)``, for world rotations ``W (A, s, 3, 3)`` and targets ``T``.

    Its squared norm is ``scale^2 * |W - T|_F^2 = scale^2 * 2 (3 - trace(T^T W))``, so with
    ``scale = sqrt(weight / 8)`` it is ``weight * sin^2(angle / 2)``, the sign-invariant
    rotation distance of quaternions ``1 - <q, q_t>^2``. The Jacobian w.r.t. a world turn
    ``a`` of each entry's joint is ``scale * [e_k]x W``, per entry: ``(A, s * 9, 3)`` (entry
    ``9 t + 3 i + j`` reads joint ``t``); written into ``out (A, s, 27)`` when given (a view
    of a caller's block).
    """
    a, s = W.shape[0], W.shape[1]
    r = (scale[..., None, None] * (W - T)).reshape(a, s * 9)
    if not jac:
        return r, None
    d = np.multiply(W.reshape(a, s, 9) @ _TURN, np.asarray(scale)[..., None], out=out)  # (A, s, 27)
    return r, d.reshape(a, s * 9, 3)


def entry_block(shape: tuple[int, int, int], start: int) -> tuple[np.ndarray, np.ndarray]:
    """A zero per-entry Jacobian block ``shape (A, m, 3)`` and a view of its entries from
    ``start`` on as ``(A, (m - start) / 9, 27)``, the shape :func:`rotation_residual` writes:
    the rows before ``start`` stay zero, the rotation rows are written at each evaluation."""
    block = np.zeros(shape)
    view = block[:, start:].reshape(shape[0], -1, 27)
    assert np.shares_memory(view, block)  # a view, not a copy
    return block, view
