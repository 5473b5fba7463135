"""A frame's terms as one sum: their losses and the gradient of their weighted total.

:class:`TermStack` puts the terms' residuals side by side (``r (A, M)``, ``M`` entries
over all terms): each constraint's loss is one sum over its entries, and ``2 w J^T r`` one
binned sum over the position and world-turn blocks of every term plus one product for
the latent's, whatever the number of terms: a per-call cost that grows with the terms'
entries, not with their count. A block row is a *pair* (a residual entry, a joint, its 3
partial derivatives): a per-entry block (``entry_joint``) has a pair per entry, a block
over ``k`` joints (``pos_joints``, ``rot_joints``) ``k`` pairs per entry
(:mod:`engine.constraints.residual`). The solver's numpy objective
(:class:`engine.solver.objective.FastObjective`) evaluates every frame through one.
"""

from __future__ import annotations

from collections.abc import Iterator, Sequence

import numpy as np

from engine.constraints.residual import Residuals, Term


def _blocks(res: Residuals, a: int) -> Iterator[tuple[bool, np.ndarray, np.ndarray | None, int]]:
    """A term's Jacobian blocks, each ``(turn, block (A, p, c), joints (k,) or None, k)``:
    ``p = m k`` pairs, entry ``i``'s ``k`` pairs consecutive; ``turn``: a block w.r.t. world
    turns, not positions (``joints``: the joints of a block over ``k`` joints; None: a
    per-entry block, whose joints are ``entry_joint``). The latent's block is not one of them."""
    if res.d_pos is not None:
        yield False, res.d_pos.reshape(a, -1, 3), res.pos_joints, res.d_pos.shape[2]
    if res.d_pos_entry is not None:
        yield False, res.d_pos_entry, None, 1
    if res.d_rot is not None:
        yield True, res.d_rot.reshape(a, -1, 3), res.rot_joints, res.d_rot.shape[2]
    if res.d_rot_entry is not None:
        yield True, res.d_rot_entry, None, 1


def _span(index: np.ndarray) -> np.ndarray | slice:
    """``index`` as a slice when it is consecutive (a view instead of a gather)."""
    if len(index) and np.array_equal(index, np.arange(index[0], index[0] + len(index))):
        return slice(int(index[0]), int(index[0]) + len(index))
    return index


class TermStack:
    """The terms of a frame as one sum (module doc).

    Parameters
    ----------
    terms : sequence of Term
        The terms, in the order of their constraints (:attr:`names`). Every constraint
        owns at least one residual entry, and each term's Jacobian blocks read the same
        joints with the same shapes at every evaluation (the layout is made once).
    joints : int
        Rows of the position and rotation gradients (the skeleton's joints).
    """

    def __init__(self, terms: Sequence[Term], joints: int = 22) -> None:
        self.terms, self.joints = list(terms), joints
        self.names = [n for t in self.terms for n in t.names]
        owned, start = [], 0
        for t in self.terms:
            owned.append(np.asarray(t.owner, dtype=np.intp) + start)
            start += len(t.names)
        self.owner = np.concatenate(owned) if owned else np.zeros(0, dtype=np.intp)
        self.entries = np.cumsum([0] + [len(o) for o in owned])  # term i's entries: entries[i]:entries[i + 1]
        # each constraint's entries together: one sum per constraint, never mixing two
        # (a non-finite entry makes only its own constraint's loss non-finite)
        self._order = np.argsort(self.owner, kind="stable")
        sorted_owner = self.owner[self._order]
        self._starts = np.flatnonzero(np.r_[len(sorted_owner) > 0, np.diff(sorted_owner) != 0])
        if not np.array_equal(sorted_owner[self._starts], np.arange(len(self.names))):
            raise ValueError("TermStack: every constraint of the terms must own a residual entry")
        self._layout: tuple[np.ndarray | slice, np.ndarray, np.ndarray | slice] | None = None
        self._layout_rows: np.ndarray | None = None
        self._weights: tuple[np.ndarray, np.ndarray] | None = None
        self._row_bins: tuple[np.ndarray, np.ndarray] | None = None

    def stack(self, res: Sequence[Residuals]) -> np.ndarray:
        """The terms' residuals ``r`` side by side: ``(A, M)``; ``res``: one per term, on ``A``
        frames (at least one term)."""
        if len(res) == 1:
            return np.asarray(res[0].r)
        return np.concatenate([r.r for r in res], axis=1)

    def losses(self, r: np.ndarray) -> np.ndarray:
        """Each constraint's loss ``(A, K)``: the squared norm of its entries of the stacked
        residual ``r (A, M)``."""
        if not len(self.names):
            return np.zeros((len(r), 0))
        r2 = r.take(self._order, axis=1)  # take: a third of fancy indexing's cost here
        r2 *= r2
        return np.add.reduceat(r2, self._starts, axis=1)

    def gradients(
        self,
        res: Sequence[Residuals],
        r: np.ndarray,
        weights: np.ndarray,
        latent: int,
        rows: np.ndarray | None = None,
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The gradients of ``sum_k weights[:, k] * loss_k`` w.r.t. the positions ``(A, 22,
        3)``, world turns ``(A, 22, 3)`` and latents ``(A, latent)``, from the terms'
        residuals ``res`` (with their Jacobians) and their stack ``r (A, M)``
        (:meth:`stack`); ``weights (A, K)``, not changed in place between calls. ``rows
        (22,)``: the row of the position and turn gradients that joint ``j``'s goes to (the
        solver's chain keeps its joints in level order); None: row ``j``.

        The position and turn blocks of all terms are one sum: each pair's ``2 w r d``
        binned (``np.bincount``) into ``(A, 44, 3)``, positions in rows ``0 .. 21``, turns
        in ``22 .. 43`` (the two gradients are views of it); a one-hot product would do
        twice the work of two, most of it on zeros."""
        a, n = len(r), self.joints
        blocks = [block for one in res for _, block, _, _ in _blocks(one, a)]
        latents = [one.d_latent for one in res if one.d_latent is not None]
        entries, bins, latent_entries = self._pairs(res, rows)
        rw = self._entry_weights(weights) * r  # (A, M): 2 w r per entry
        if blocks:
            d = blocks[0] if len(blocks) == 1 else np.concatenate(blocks, axis=1)  # (A, P, 3)
            x = (rw[:, entries] if isinstance(entries, slice) else rw.take(entries, axis=1))[:, :, None] * d
            flat: np.ndarray = np.bincount(self._bins(bins, a), weights=x.reshape(-1), minlength=a * 6 * n)
        else:
            flat = np.zeros(a * 6 * n)
        g = flat.reshape(a, 2 * n, 3)
        if latents:
            d = latents[0] if len(latents) == 1 else np.concatenate(latents, axis=1)  # (A, P', L)
            g_z = (rw[:, None, latent_entries] @ d)[:, 0]
        else:
            g_z = np.zeros((a, latent))
        return g[:, :n], g[:, n:], g_z

    def _entry_weights(self, weights: np.ndarray) -> np.ndarray:
        """``2 weights[:, owner]`` ``(A, M)``: kept while the solve passes the same weights
        array (a frame-by-frame solve passes one array at every iteration)."""
        kept = self._weights
        if kept is None or kept[0] is not weights:
            kept = self._weights = (weights, 2.0 * weights[:, self.owner])
        return kept[1]

    def _bins(self, bins: np.ndarray, a: int) -> np.ndarray:
        """The bins ``(A P 3,)`` of ``A`` frames' pairs: frame ``f``'s are ``bins + 6 * 22 f``."""
        kept = self._row_bins
        if kept is None or kept[0] is not bins or len(kept[1]) != a * len(bins):
            offsets = 6 * self.joints * np.arange(a)
            kept = self._row_bins = (bins, (offsets[:, None] + bins).reshape(-1))
        return kept[1]

    def _pairs(
        self, res: Sequence[Residuals], rows: np.ndarray | None
    ) -> tuple[np.ndarray | slice, np.ndarray, np.ndarray | slice]:
        """The stacked entry each position or turn pair multiplies ``(P,)`` (or a slice), the
        bins ``(P 3,)`` of its three partial derivatives in a frame's ``(44, 3)`` gradient,
        and the entries of the latent blocks (made at the first call, again only for other
        ``rows``)."""
        if self._layout is not None and self._layout_rows is rows:
            return self._layout
        entries, joints, latent = [np.zeros(0, np.intp)], [np.zeros(0, np.intp)], [np.zeros(0, np.intp)]
        for start, one in zip(self.entries[:-1], res):
            m = np.asarray(one.r).shape[1]
            for turn, _, block_joints, k in _blocks(one, 1):
                entries.append(start + np.repeat(np.arange(m), k))
                if block_joints is None:
                    assert one.entry_joint is not None  # a per-entry block comes with its joints
                    block_joints = one.entry_joint
                else:
                    block_joints = np.tile(block_joints, m)
                # each pair's row of the gradient array: rows[joint] (the joint itself without rows)
                block_joints = np.asarray(block_joints) if rows is None else rows[block_joints]
                joints.append(block_joints + (self.joints if turn else 0))
            if one.d_latent is not None:
                latent.append(start + np.arange(m))
        bins = (3 * np.concatenate(joints)[:, None] + np.arange(3)).reshape(-1)
        self._layout = (_span(np.concatenate(entries)), bins, _span(np.concatenate(latent)))
        self._layout_rows = rows
        return self._layout
