"""An exact prefilter for the pose bank's nearest-neighbour lookup
(:class:`engine.solver.tracker_prior.PoseBank`).

A lookup compares the query with every bank row over the combination's columns: the
whole ``(N, 55)`` float32 table (~20 MB) is read once per frame. The prefilter keeps, per
combination, the rows projected onto their ``rank`` principal directions plus the length
of what the projection leaves out. For any row ``t`` and query ``q``,

    |t - q|^2 = |P(t - q)|^2 + |R(t - q)|^2 >= |P t - P q|^2 + (|R t| - |R q|)^2,

(``P`` the projection, ``R`` its orthogonal complement, the triangle inequality on the
second term), so a row whose bound exceeds the ``k``-th smallest distance of ``k`` known
rows (the previous frame's neighbours: poses change little between frames) cannot be a
neighbour. Only the rows that survive are compared exactly, with the same float32
products the full lookup uses, so the neighbours and their order are the full lookup's.
The bound is evaluated in float32 and the distances carry float32 rounding, so the
test keeps a margin (:data:`MARGIN` times the largest magnitudes involved) that is far
above both rounding errors: a row is dropped only when it is certainly farther.

The bound of every row is one float32 product with the ``(rank + 2, N)`` table (a third
of the full table's bytes); a clip's frames take it for :data:`FRAMES` queries at once
(:meth:`Prefilter.bounds`), one matrix product that reads the table once for all of them.
Blocks of consecutive rows with a centre and a radius do not
pay here: on the shipped bank a block bound rules out about half the rows, and gathering
the other half costs more than reading them all (docs/performance.md).

A realtime lookup reads the bounds of every row only now and then (:class:`Neighbourhood`).
The bound is a squared distance between two points of a ``rank + 1``-dimensional space,
``u(t) = [Pt, |Rt|]`` and ``u(q)``, so once every row's distance to one query's point is
known, the triangle inequality bounds every row's distance to any later query from below
by that distance less how far the queries' points are apart. A live query moves about a
tenth of the search radius per frame; the rows within the radius plus :data:`SLACK` of
the query that read the whole table serve the next few frames, each of which computes the
bounds of the few thousand of them that may still pass.
"""

from __future__ import annotations

import numpy as np
import torch

#: Principal directions kept per combination (16 of 55 columns: about 4 MB per combination).
RANK = 16
#: Relative margin of the pruning test, far above float32 rounding of 55-term sums (~4e-6).
MARGIN = 1e-4
#: Rows compared exactly are gathered in blocks of this many (the float32 product of a
#: gathered block gives each row the bits it has in the whole table's product; a ragged
#: tail takes another summation path).
BLOCK = 16
#: Above this share of the bank surviving, the whole table is compared instead.
MAX_SHARE = 0.25
#: Queries whose bounds :meth:`Prefilter.bounds` computes in one product: 16 rows of the
#: shipped bank's ~1e5 bounds, 6 MB, where each query alone read the 7 MB table (16 and
#: 32 measured alike, 64 and 128 slower: docs/performance.md).
FRAMES = 16
#: How far beyond a lookup's search radius (standardised feature units, where a live
#: query's point moves ~0.4 a frame and the radius is ~4) a :class:`Neighbourhood` keeps
#: rows: about 7 % of the shipped bank, whose bounds then serve ~3.5 frames on average.
SLACK = 1.0


class Prefilter:
    """Lower bounds of the squared distances between bank rows and a query.

    Parameters
    ----------
    rows : Tensor (N, D_c) float32
        The combination's standardised features of every bank frame.
    rank : int
        Principal directions kept.
    gram : ndarray (D_c, D_c), optional
        ``rows.T @ rows`` in float64 if known (e.g. the combination's block of its
        anchor table's Gram matrix: one product per anchor instead of one per combination).
    """

    def __init__(self, rows: torch.Tensor, rank: int = RANK, gram: np.ndarray | None = None) -> None:
        x = rows.double().numpy()
        rank = min(rank, x.shape[1])
        _, vecs = np.linalg.eigh(x.T @ x if gram is None else gram)  # ascending eigenvalues
        self.basis = np.ascontiguousarray(vecs[:, ::-1][:, :rank])  # (D_c, rank) float64
        proj = x @ self.basis
        sq = (x * x).sum(1)
        pn = (proj * proj).sum(1)
        res = np.sqrt(np.maximum(sq - pn, 0.0))
        # |Pt - Pq|^2 + (|Rt| - |Rq|)^2 = [Pt, |Rt|, |Pt|^2 + |Rt|^2] . [-2Pq, -2|Rq|, 1] + |q|^2:
        # one product over the rows, the query's own term added to the threshold instead
        # kept column by column (rank + 2, N): the product is then a sum of rank + 2 scaled
        # columns, ~1.6x faster than N dot products of length rank + 2 on one core
        self.columns = torch.from_numpy(np.vstack((proj.T, res, pn + res * res)).astype(np.float32))
        self.largest = float(sq.max())  # the largest squared row length, for the margin
        self._by_row: torch.Tensor | None = None  # columns.T, made by the first bound_at of rows

    def bound(self, q: np.ndarray) -> tuple[torch.Tensor, float, float]:
        """``(b (N,) float32, offset, margin)`` for the query ``q (D_c,)`` (the float32
        query's values), in squared standardised units: ``b + offset - margin`` is below
        every row's true squared distance to ``q``."""
        q = np.asarray(q, dtype=np.float64)
        qq = float(q @ q)
        return self.bound_at(self.point(q)), qq, self.margin(qq)

    def bounds(self, q: np.ndarray) -> torch.Tensor:
        """The ``b`` of :meth:`bound` for ``F`` queries ``q (F, D_c)``: ``(F, N)`` float32,
        one product (each row's sums may round otherwise than :meth:`bound`'s; the
        margin covers both)."""
        q = np.asarray(q, dtype=np.float64)
        pq = q @ self.basis
        rq = np.sqrt(np.maximum((q * q).sum(1) - (pq * pq).sum(1), 0.0))
        w = np.concatenate((-2.0 * pq, -2.0 * rq[:, None], np.ones((len(q), 1))), axis=1)
        return torch.from_numpy(w.astype(np.float32)) @ self.columns

    def point(self, q: np.ndarray) -> np.ndarray:
        """``u(q) = [Pq, |Rq|]`` ``(rank + 1,)`` float64 of the query ``q (D_c,)``: the
        bound is ``|u(t) - u(q)|^2 - |q|^2`` for the rows' points ``u(t)``."""
        q = np.asarray(q, dtype=np.float64)
        pq = q @ self.basis
        return np.append(pq, np.sqrt(max(float(q @ q) - float(pq @ pq), 0.0)))

    def bound_at(self, u: np.ndarray, rows: torch.Tensor | None = None) -> torch.Tensor:
        """The ``b`` of :meth:`bound` for the query whose :meth:`point` is ``u``, of every
        row ``(N,)`` or of ``rows`` only ``(len(rows),)`` (rounded as a product of their
        own; the margin covers it). ``rows`` are gathered from a row-major copy of the
        columns (a gather across the columns' rows takes 5x longer), made on first use:
        only live lookups ask for rows."""
        # [Pt, |Rt|, |Pt|^2 + |Rt|^2] . [-2Pq, -2|Rq|, 1]
        w = torch.from_numpy(np.append(-2.0 * u, 1.0).astype(np.float32))
        if rows is None:
            return w @ self.columns
        if self._by_row is None:
            self._by_row = self.columns.T.contiguous()
        return self._by_row.index_select(0, rows) @ w

    def margin(self, qq: float) -> float:
        """The test's margin for a query of squared length ``qq``."""
        return MARGIN * (1.0 + self.largest + qq)

    def candidates(self, q: np.ndarray, worst: float, b: torch.Tensor | None = None) -> torch.Tensor:
        """Indices (ascending) of the rows that may be nearer than ``worst`` (a computed
        distance ``norms - 2 t.q`` of the query ``q (D_c,)``, float32 values): every row
        whose float32 bound passes the test of :func:`nearest`; ``b``: the query's row of
        :meth:`bounds`, if made."""
        if b is None:
            b, _, margin = self.bound(q)
        else:
            q = np.asarray(q, dtype=np.float64)
            margin = self.margin(float(q @ q))
        # numpy's nonzero, not torch's: a third of the time on the bank's ~1e5 rows
        return torch.from_numpy(np.flatnonzero(b.numpy() <= worst + 2.0 * margin))


class Neighbourhood:
    """The rows near one query, which bound the candidates of the queries after it.

    :meth:`candidates` gives what :meth:`Prefilter.candidates` gives (every row whose
    bound may pass), reading the whole table's bounds only when the query's search ball
    has left the ball :meth:`candidates` last kept the rows of (see the module doc).
    Which rows it returns beyond the ones that must be there depends on the history,
    never the neighbours :func:`nearest` finds among them.
    """

    def __init__(self) -> None:
        self.centre: np.ndarray | None = None  # u(q) of the query that read the whole table
        self.reach = -1.0  # the radius of the ball whose rows are kept
        self.rows = torch.zeros(0, dtype=torch.int64)  # (M,) ascending
        self.low = np.zeros(0)  # (M,) float64: below each kept row's distance to centre
        self.refreshed = 0  # how often the whole table was read

    def candidates(self, pre: Prefilter, q: np.ndarray, worst: float) -> torch.Tensor:
        """Indices (ascending) of the rows that may be nearer than ``worst`` to ``q
        (D_c,)`` (as :meth:`Prefilter.candidates`)."""
        q64 = np.asarray(q, dtype=np.float64)
        qq = float(q64 @ q64)
        margin = pre.margin(qq)
        # a row passes the test only if |u(t) - u(q)|^2 <= worst + |q|^2 + 3 margin
        radius = float(np.sqrt(max(worst + qq + 3.0 * margin, 0.0)))
        u = pre.point(q64)
        moved = float(np.linalg.norm(u - self.centre)) if self.centre is not None else np.inf
        if radius + moved > self.reach:  # the kept ball no longer holds the search ball
            bb = pre.bound_at(u).numpy()
            self.centre, self.reach = u, radius + SLACK
            # low = sqrt(b + |q|^2 - margin) is below |u(t) - centre|; a row left out has
            # low > reach (the extra margin covers the float32 comparison)
            kept = np.flatnonzero(bb <= self.reach**2 - qq + 2.0 * margin)
            low = np.sqrt(np.maximum(bb[kept].astype(np.float64) + (qq - margin), 0.0))
            self.rows, self.low = torch.from_numpy(kept), low
            self.refreshed += 1
            return torch.from_numpy(np.flatnonzero(bb <= worst + 2.0 * margin))
        # |u(t) - u(q)| >= |u(t) - centre| - moved >= low - moved; 1e-9 for the float64 sums
        near = self.rows[torch.from_numpy(self.low - moved <= radius + 1e-9)]
        b = pre.bound_at(u, near).numpy()
        return near[torch.from_numpy(b <= worst + 2.0 * margin)]


def distances(table: torch.Tensor, norms: torch.Tensor, q: torch.Tensor, rows: torch.Tensor) -> torch.Tensor:
    """``norms - 2 table @ q`` of ``rows`` only ``(len(rows),)``, each with the bits the
    whole table's product gives it (the gathered block is padded to :data:`BLOCK` rows)."""
    m = len(rows)
    pad = -m % BLOCK
    if pad:
        rows_p = torch.cat((rows, rows[-1:].expand(pad)))
    else:
        rows_p = rows
    return norms[rows] - 2.0 * (table.index_select(0, rows_p) @ q)[:m]


def nearest(
    table: torch.Tensor,
    norms: torch.Tensor,
    q: torch.Tensor,
    q_cols: np.ndarray,
    pre: Prefilter,
    hint: torch.Tensor | None,
    k: int,
    bound: torch.Tensor | None = None,
    near: Neighbourhood | None = None,
) -> torch.Tensor:
    """Indices ``(k,)`` of the ``k`` rows with the smallest ``norms - 2 table @ q``, in
    increasing order, as ``topk`` over the whole table gives them; ``hint`` (at least
    ``k`` row indices, e.g. the previous frame's neighbours) bounds the search, ``q_cols``
    is the query over the combination's columns (float32 values), ``bound`` its row of
    :meth:`Prefilter.bounds` if made, ``near`` the rows near the combination's last
    queries (a realtime lookup's, updated here; used when ``bound`` is not given)."""
    n = len(table)
    if hint is not None and len(hint) >= k:
        d_hint = distances(table, norms, q, hint)
        # the k-th smallest of k values is their largest (a hint is the last k neighbours)
        worst = float(d_hint.max() if len(hint) == k else d_hint.topk(k, largest=False).values[-1])
        # computed d = |t - q|^2 - |q|^2 (+ rounding) and bound = b + |q|^2, so a row can be
        # nearer than the k-th known one only when b + |q|^2 - margin <= worst + |q|^2 + margin
        if near is not None and bound is None:
            keep = near.candidates(pre, q_cols, worst)
        else:
            keep = pre.candidates(q_cols, worst, bound)
        if len(keep) <= MAX_SHARE * n:
            d = distances(table, norms, q, keep)
            return keep[d.topk(k, largest=False).indices]
    return (norms - 2.0 * (table @ q)).topk(k, largest=False).indices
