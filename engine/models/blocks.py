"""Block-sparse matrix products for the skeletal layers of a batch pass.

A skeletal layer (:class:`engine.models.skeletal.SkeletalLinear`) maps a batch of node
features ``x (B, N_in * C_in)`` to ``y (B, N_out * C_out)`` with a matrix that is zero
wherever a node does not read another. That matrix is stored as a few dense rectangles:
consecutive output nodes are grouped, the input nodes a group reads are covered by one or
more contiguous ranges, and each (group, range) rectangle is one BLAS product on column
slices of ``x`` and ``y`` (strided views: no gather, no copy), the first of a group
setting its columns of ``y`` and the others adding to them. The grouping and the ranges
minimise ``entries + call_cost per rectangle`` by dynamic programming over the node order
(:func:`plan_rectangles`), as the solver's decoder groups its runs
(:mod:`engine.models.fused`). Entries outside every rectangle are
zero in the dense matrix, so the products are the same sums, with fewer zero terms.

The three products a layer's gradients need are each other's derivatives, so each is an
autograd function whose backward calls the other two: the forward product ``y = x S(w)``,
the transposed product ``g S(w)^T`` (the input gradient) and the weight gradient (``x^T g``
on the rectangles). A second-order gradient (the VAE's continuity loss) runs through them
like through ``mm``. A backward computes only the gradients the running pass reads (as
autograd's own products do), so the continuity loss's inner gradient with respect to the
latent takes no weight gradients.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import torch


@dataclass(frozen=True)
class BlockPlan:
    """The rectangles of one block-sparse matrix ``S (n_in, n_out)``, stored flat.

    Attributes
    ----------
    spans : tuple of (r0, r1, c0, c1, offset)
        ``y[:, r0:r1] += x[:, c0:c1] @ w[offset : offset + (c1 - c0) * (r1 - r0)]`` viewed
        ``(c1 - c0, r1 - r0)``; the row ranges cover the output features, and a span's rows
        are either an earlier span's or no earlier span's.
    n_in, n_out : int
        Input and output features.
    size : int
        Entries of the flat weight vector.
    sets : tuple of bool
        Per span: its rows are no earlier span's, so the product sets them (bias
        included); the others add to them.
    writes : tuple of bool
        Per span: no earlier span reads its input columns, so the transposed product
        writes them (the others add to what is there).
    zero : tuple of (start, stop)
        The input columns no writing span covers: zeroed before the transposed product.
    """

    spans: tuple[tuple[int, int, int, int, int], ...]
    n_in: int
    n_out: int
    size: int
    sets: tuple[bool, ...]
    writes: tuple[bool, ...]
    zero: tuple[tuple[int, int], ...]

    @classmethod
    def of(cls, spans: list[tuple[int, int, int, int]], n_in: int, n_out: int) -> BlockPlan:
        """The plan of rectangles ``(r0, r1, c0, c1)`` (features), stored in that order."""
        placed, offset = [], 0
        rows_seen: set[tuple[int, int]] = set()
        rows_touched = np.zeros(n_out, dtype=bool)
        touched = np.zeros(n_in, dtype=bool)
        written = np.zeros(n_in, dtype=bool)
        sets, writes = [], []
        for r0, r1, c0, c1 in spans:
            placed.append((r0, r1, c0, c1, offset))
            offset += (r1 - r0) * (c1 - c0)
            sets.append((r0, r1) not in rows_seen)
            if sets[-1] and rows_touched[r0:r1].any():
                raise ValueError(f"rows {r0}:{r1} overlap an earlier span's without being its rows")
            rows_seen.add((r0, r1))
            rows_touched[r0:r1] = True
            writes.append(not touched[c0:c1].any())
            if writes[-1]:
                written[c0:c1] = True
            touched[c0:c1] = True
        if not rows_touched.all():
            raise ValueError("the spans leave output rows uncovered")
        edges = np.flatnonzero(np.diff(np.r_[False, ~written, False].astype(np.int8)))
        zero = tuple((int(a), int(b)) for a, b in zip(edges[::2], edges[1::2]))
        return cls(tuple(placed), n_in, n_out, offset, tuple(sets), tuple(writes), zero)


def _cover(cols: list[int], entries_per_col: int, call_cost: float) -> tuple[float, list[tuple[int, int]]]:
    """Cover the sorted node indices ``cols`` by ranges ``(first, stop)``, at least
    ``entries_per_col * width + call_cost`` summed over the ranges. A range ends only
    where ``cols`` has a gap (splitting consecutive nodes saves nothing)."""
    runs: list[list[int]] = []
    for c in cols:
        if runs and c == runs[-1][1]:
            runs[-1][1] = c + 1
        else:
            runs.append([c, c + 1])
    m = len(runs)
    best, start = [0.0] + [np.inf] * m, [0] * (m + 1)
    for t in range(1, m + 1):
        for u in range(t):
            cost = best[u] + entries_per_col * (runs[t - 1][1] - runs[u][0]) + call_cost
            if cost < best[t]:
                best[t], start[t] = cost, u
    ranges, t = [], m
    while t > 0:
        u = start[t]
        ranges.append((runs[u][0], runs[t - 1][1]))
        t = u
    return best[m], ranges[::-1]


def plan_rectangles(
    reads: list[list[int]], row_width: int, col_width: int, call_cost: float
) -> list[tuple[int, int, int, int]]:
    """Cover the node blocks that output nodes read by rectangles: consecutive output
    nodes grouped, and each group's input nodes by one or more ranges, at least
    ``entries + call_cost`` summed over the rectangles.

    Parameters
    ----------
    reads : list of list of int
        Per output node, the input nodes it reads (not empty).
    row_width, col_width : int
        Features per output node and per input node (a rectangle of ``r`` output and ``c``
        input nodes has ``r * row_width * c * col_width`` entries).
    call_cost : float
        Entries one more rectangle must save to be worth its products.

    Returns
    -------
    list of (first output node, stop, first input node, stop)
        Grouped by output nodes, in order.
    """
    n = len(reads)
    best: list[float] = [0.0] + [np.inf] * n
    choice: list[tuple[int, list[tuple[int, int]]]] = [(0, [])] * (n + 1)
    for e in range(1, n + 1):
        used: set[int] = set()
        for s in range(e - 1, -1, -1):
            used.update(reads[s])
            cost, ranges = _cover(sorted(used), (e - s) * row_width * col_width, call_cost)
            if best[s] + cost < best[e]:
                best[e], choice[e] = best[s] + cost, (s, ranges)
    rects: list[tuple[int, int, int, int]] = []
    e = n
    while e > 0:
        s, ranges = choice[e]
        rects[:0] = [(s, e, c0, c1) for c0, c1 in ranges]
        e = s
    return rects


def _blocks(w: torch.Tensor, plan: BlockPlan, transpose: bool = False) -> list[torch.Tensor]:
    """The rectangles of the flat weights ``w`` as ``(c1 - c0, r1 - r0)`` views, or
    transposed (one strided view each)."""
    if not w.is_contiguous():
        w = w.contiguous()
    base = w.storage_offset()
    if transpose:
        return [w.as_strided((r1 - r0, c1 - c0), (1, r1 - r0), base + o) for r0, r1, c0, c1, o in plan.spans]
    return [w.as_strided((c1 - c0, r1 - r0), (r1 - r0, 1), base + o) for r0, r1, c0, c1, o in plan.spans]


def _product(x: torch.Tensor, w: torch.Tensor, bias: torch.Tensor | None, plan: BlockPlan) -> torch.Tensor:
    y = x.new_empty(x.shape[0], plan.n_out)
    for (r0, r1, c0, c1, _), blk, first in zip(plan.spans, _blocks(w, plan), plan.sets):
        if not first:
            y[:, r0:r1].addmm_(x[:, c0:c1], blk)
        elif bias is None:
            torch.mm(x[:, c0:c1], blk, out=y[:, r0:r1])
        else:
            torch.addmm(bias[r0:r1], x[:, c0:c1], blk, out=y[:, r0:r1])
    return y


def _transposed(g: torch.Tensor, w: torch.Tensor, plan: BlockPlan) -> torch.Tensor:
    gx = g.new_empty(g.shape[0], plan.n_in)
    for a, b in plan.zero:
        gx[:, a:b] = 0.0
    for (r0, r1, c0, c1, _), blk, write in zip(plan.spans, _blocks(w, plan, transpose=True), plan.writes):
        if write:
            torch.mm(g[:, r0:r1], blk, out=gx[:, c0:c1])
        else:
            gx[:, c0:c1].addmm_(g[:, r0:r1], blk)
    return gx


def _weight_grad(x: torch.Tensor, g: torch.Tensor, plan: BlockPlan) -> torch.Tensor:
    gw = x.new_empty(plan.size)
    xt = x.t()
    for (r0, r1, c0, c1, _), blk in zip(plan.spans, _blocks(gw, plan)):
        torch.mm(xt[c0:c1], g[:, r0:r1], out=blk)
    return gw


def _wanted(t: torch.Tensor, needed: bool) -> bool:
    """Whether the running backward pass reads the gradient of input ``t``: autograd's
    own products skip a gradient no requested input depends on (``autograd.grad`` with
    respect to the latent takes no weight gradients), and these do the same."""
    if not needed:
        return False
    if t.grad_fn is None:
        return True
    try:
        return bool(torch._C._will_engine_execute_node(t.grad_fn))
    except RuntimeError:  # not inside a backward pass
        return True


def _rows(t: torch.Tensor) -> torch.Tensor:
    """``t`` with unit column stride (a gradient may arrive broadcast)."""
    return t if t.stride(-1) == 1 and t.stride(0) >= t.shape[1] else t.contiguous()


class _Product(torch.autograd.Function):
    @staticmethod
    def forward(ctx, x, w, bias, plan):
        ctx.save_for_backward(x, w)
        ctx.plan = plan
        return _product(x, w, bias, plan)

    @staticmethod
    def backward(ctx, gy):
        x, w = ctx.saved_tensors
        gy = _rows(gy)
        need_x, need_w, need_b = ctx.needs_input_grad[:3]
        gx = transposed(gy, w, ctx.plan) if _wanted(x, need_x) else None
        gw = weight_grad(x, gy, ctx.plan) if _wanted(w, need_w) else None
        gb = gy.sum(0) if need_b else None
        return gx, gw, gb, None


class _Transposed(torch.autograd.Function):
    @staticmethod
    def forward(ctx, g, w, plan):
        ctx.save_for_backward(g, w)
        ctx.plan = plan
        return _transposed(g, w, plan)

    @staticmethod
    def backward(ctx, h):
        g, w = ctx.saved_tensors
        h = _rows(h)
        need_g, need_w = ctx.needs_input_grad[:2]
        gg = product(h, w, None, ctx.plan) if _wanted(g, need_g) else None
        gw = weight_grad(h, g, ctx.plan) if _wanted(w, need_w) else None
        return gg, gw, None


class _WeightGrad(torch.autograd.Function):
    @staticmethod
    def forward(ctx, x, g, plan):
        ctx.save_for_backward(x, g)
        ctx.plan = plan
        return _weight_grad(x, g, plan)

    @staticmethod
    def backward(ctx, hw):
        x, g = ctx.saved_tensors
        need_x, need_g = ctx.needs_input_grad[:2]
        gx = transposed(g, hw, ctx.plan) if _wanted(x, need_x) else None
        gg = product(x, hw, None, ctx.plan) if _wanted(g, need_g) else None
        return gx, gg, None


def _scatter(rows: torch.Tensor, passes: tuple[tuple[torch.Tensor, torch.Tensor], ...], count: int) -> torch.Tensor:
    out = rows.new_zeros(count, rows.shape[1])
    for dst, src in passes:
        out.index_add_(0, dst, rows.index_select(0, src))
    return out


class _Scatter(torch.autograd.Function):
    @staticmethod
    def forward(ctx, rows, passes, back, unused, count):
        ctx.back, ctx.unused = back, unused
        return _scatter(rows, passes, count)

    @staticmethod
    def backward(ctx, g):
        grad = g.index_select(0, ctx.back)
        if ctx.unused.numel():
            grad.index_fill_(0, ctx.unused, 0.0)
        return grad, None, None, None, None


def scatter_rows(
    rows: torch.Tensor,
    passes: tuple[tuple[torch.Tensor, torch.Tensor], ...],
    back: torch.Tensor,
    unused: torch.Tensor,
    count: int,
) -> torch.Tensor:
    """``count`` rows of zeros with row ``src[m]`` of ``rows`` added to row ``dst[m]`` for
    every ``(dst, src)`` of ``passes`` in turn (a layer's weights into its rectangles). No
    pass names a row of the result twice, so the sums are made in one order on any
    device (atomic adds to one row would not be). Every row of ``rows`` is read once at
    most, so the gradient is a gather: row ``r`` of ``rows`` takes the gradient of row
    ``back[r]``, and the rows listed in ``unused`` (read by no rectangle) take zero."""
    if _tracked(rows):
        return _Scatter.apply(rows, passes, back, unused, count)
    return _scatter(rows, passes, count)


def _tracked(*ts: torch.Tensor | None) -> bool:
    return torch.is_grad_enabled() and any(t is not None and t.requires_grad for t in ts)


def product(x: torch.Tensor, w: torch.Tensor, bias: torch.Tensor | None, plan: BlockPlan) -> torch.Tensor:
    """``x (B, n_in) @ S(w) + bias`` with ``S(w)`` the block-sparse matrix of ``plan`` and
    the flat weights ``w (size,)``; ``x`` with unit column stride. ``(B, n_out)``."""
    if _tracked(x, w, bias):
        return _Product.apply(x, w, bias, plan)
    return _product(x, w, bias, plan)


def transposed(g: torch.Tensor, w: torch.Tensor, plan: BlockPlan) -> torch.Tensor:
    """``g (B, n_out) @ S(w)^T``: the input gradient of :func:`product`. ``(B, n_in)``."""
    if _tracked(g, w):
        return _Transposed.apply(g, w, plan)
    return _transposed(g, w, plan)


def weight_grad(x: torch.Tensor, g: torch.Tensor, plan: BlockPlan) -> torch.Tensor:
    """``x^T g`` on the rectangles of ``plan``, flat like the weights: the weight gradient
    of :func:`product`. ``(size,)``."""
    if _tracked(x, g):
        return _WeightGrad.apply(x, g, plan)
    return _weight_grad(x, g, plan)
