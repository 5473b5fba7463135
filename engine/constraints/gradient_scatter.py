"""Index arithmetic that carries a term's Jacobian blocks into per-joint gradients.

:meth:`engine.constraints.residual.Term.accumulate` and :meth:`~engine.constraints.residual.Term.losses`
turn ``2 w J^T r`` and ``|r|^2`` into sums over joints and constraints: a joint's row of
a gradient array (:func:`gradient_rows`), a block's entries summed by one matrix product
(:func:`entry_sum`), a scatter that counts a repeated joint twice (:func:`scatter_add`),
and the 0/1 matrices that sum entries by constraint (:func:`members`) or by joint
(:func:`one_hot`), cached because a term's index arrays never change.
"""

from __future__ import annotations

import numpy as np


def gradient_rows(joints: np.ndarray, rows: np.ndarray | None) -> np.ndarray:
    """The rows ``rows[joints]`` ``(k,)`` of a gradient array for ``joints (k,)`` (``joints`` itself without ``rows (22,)``)."""
    return joints if rows is None else rows[joints]


def entry_sum(rw: np.ndarray, d: np.ndarray) -> np.ndarray:
    """``sum_m rw[a, 0, m] d[a, m, k, c]`` as one matrix product: ``(A, k, 3)``."""
    a, m, k, _ = d.shape
    return (rw @ d.reshape(a, m, 3 * k)).reshape(a, k, 3)


_DISTINCT: dict[bytes, bool] = {}  # joint lists seen -> whether no joint repeats (terms reuse theirs)


def scatter_add(out: np.ndarray, joints: np.ndarray, g: np.ndarray) -> None:
    """``out[:, joints] += g`` (``out (A, 22, 3)``, ``joints (k,)``, ``g (A, k, 3)``), counting a joint listed twice twice."""
    key = joints.tobytes()
    distinct = _DISTINCT.get(key)
    if distinct is None:
        if len(_DISTINCT) > 4096:
            _DISTINCT.clear()
        distinct = _DISTINCT[key] = len(np.unique(joints)) == len(joints)
    if distinct:
        out[:, joints] += g
    else:
        np.add.at(out, (slice(None), joints), g)  # type: ignore[arg-type]  # numpy's stubs refuse a tuple index


_INDICATORS: dict[tuple[bytes, int, bool], np.ndarray] = {}  # index arrays seen -> their 0/1 matrix (shared)


def _indicator(index: np.ndarray, count: int, by_entry: bool) -> np.ndarray:
    """The 0/1 matrix of ``index (m,)`` over ``count`` classes: ``(m, count)`` with 1 at
    ``[i, index[i]]`` when ``by_entry``, else its transpose ``(count, m)`` (C order either
    way). Cached: a term's index arrays never change, and frame after frame share theirs."""
    key = (index.tobytes(), count, by_entry)
    out = _INDICATORS.get(key)
    if out is None:
        if len(_INDICATORS) > 4096:
            _INDICATORS.clear()
        m = np.arange(len(index))
        if by_entry:
            out = np.zeros((len(index), count))
            out[m, index] = 1.0
        else:
            out = np.zeros((count, len(index)))
            out[index, m] = 1.0
        _INDICATORS[key] = out
    return out


def members(owner: np.ndarray, count: int) -> np.ndarray:
    """``(m, count)``: ``r2 @ members(owner)`` sums each constraint's squared entries."""
    return _indicator(owner, count, by_entry=True)


def one_hot(joints: np.ndarray, count: int) -> np.ndarray:
    """``(count, m)``: ``one_hot(joints) @ x`` sums the rows ``x (A, m, c)`` of each joint."""
    return _indicator(joints, count, by_entry=False)
