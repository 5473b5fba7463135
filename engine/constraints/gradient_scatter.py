"""Index arithmetic that carries Jacobian blocks into per-joint gradients and residual
entries into per-constraint losses: a joint's row of a gradient array
(:func:`gradient_rows`, for :class:`~engine.constraints.term_stack.TermStack`) and the
0/1 matrix that sums one term's entries by constraint (:func:`members`, for
:meth:`Term.losses <engine.constraints.residual.Term.losses>` on numpy or torch arrays).
"""

from __future__ import annotations

import numpy as np


def gradient_rows(joints: np.ndarray, rows: np.ndarray | None) -> np.ndarray:
    """The rows ``rows[joints]`` ``(k,)`` of a gradient array for ``joints (k,)`` (``joints`` itself without ``rows (22,)``)."""
    return joints if rows is None else rows[joints]


_MEMBERS: dict[tuple[bytes, int], np.ndarray] = {}  # owner arrays seen -> their 0/1 matrix (shared)


def members(owner: np.ndarray, count: int) -> np.ndarray:
    """``(m, count)``, 1 at ``[i, owner[i]]``: ``r2 @ members(owner)`` sums each
    constraint's squared entries. Cached: a term's owners never change, and frame after
    frame share theirs."""
    key = (owner.tobytes(), count)
    out = _MEMBERS.get(key)
    if out is None:
        if len(_MEMBERS) > 4096:
            _MEMBERS.clear()
        out = np.zeros((len(owner), count))
        out[np.arange(len(owner)), owner] = 1.0
        _MEMBERS[key] = out
    return out
