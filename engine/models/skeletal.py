"""Skeleton-aware building blocks: masked ("skeletal") linear layers and joint pooling.

Following SparsePoser (Ponton et al. 2023, after Aberman et al. 2020), a joint only
sees its neighbours in the joint graph (distance <= 2) through a masked weight matrix,
and the skeleton is pooled by merging consecutive joints until a primal skeleton is
left: 22 -> 14 -> 9 -> 6 nodes here (root, two legs, two arms, torso).
"""

from __future__ import annotations

from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass

import numpy as np
import torch
from torch import nn

from engine import skeleton as sk
from engine.models import blocks

#: Pooling groups per level: each entry lists the nodes of the level below it merges.
POOL_GROUPS: tuple[tuple[tuple[int, ...], ...], ...] = (
    # 22 -> 14: hip+knee, ankle+toe, clavicle+shoulder, elbow+wrist; root, spine, neck kept
    ((0,), (1, 2), (3, 4), (5, 6), (7, 8), (9,), (10,), (11,), (12,), (13,), (14, 15), (16, 17), (18, 19), (20, 21)),
    # 14 -> 9: each limb one node, lowerback+upperback
    ((0,), (1, 2), (3, 4), (5, 6), (7,), (8,), (9,), (10, 11), (12, 13)),
    # 9 -> 6: the torso and neck chain becomes one node
    ((0,), (1,), (2,), (3, 4, 5, 6), (7,), (8,)),
)


def _edges_level0() -> set[tuple[int, int]]:
    return {(j, p) for j, p in enumerate(sk.PARENTS) if p >= 0}


def level_edges() -> list[set[tuple[int, int]]]:
    """Undirected edges of the node graph at each level (0 = the full skeleton)."""
    levels = [_edges_level0()]
    for groups in POOL_GROUPS:
        owner = {m: g for g, members in enumerate(groups) for m in members}
        levels.append({(owner[a], owner[b]) for a, b in levels[-1] if owner[a] != owner[b]})
    return levels


def neighbour_mask(num_nodes: int, edges: set[tuple[int, int]], distance: int = 2) -> np.ndarray:
    """Boolean (num_nodes, num_nodes): True where graph distance <= ``distance``."""
    adj = np.eye(num_nodes, dtype=bool)
    for a, b in edges:
        adj[a, b] = adj[b, a] = True
    reach = np.eye(num_nodes, dtype=bool)
    for _ in range(distance):
        reach = reach | (reach.astype(int) @ adj.astype(int) > 0)
    return reach


#: Batch size from which :class:`SkeletalLinear` multiplies by its block-sparse matrix.
BLOCKS_FROM = 64

#: Cost of one more rectangle in a layer's block-sparse matrix (:mod:`engine.models.blocks`),
#: in weight entries: about what one more product's call costs at a training batch.
BLOCK_CALL_COST = 2000


def unpool_source(groups: tuple[tuple[int, ...], ...]) -> tuple[int, ...]:
    """The node of the coarser level every node copies when unpooling by ``groups``: the
    rows of :func:`unpool_matrix`'s ones."""
    owner = {m: g for g, members in enumerate(groups) for m in members}
    return tuple(owner[m] for m in range(len(owner)))


@dataclass(frozen=True)
class Layout:
    """Where a :class:`SkeletalLinear`'s weights lie in its block-sparse matrix: the
    plan, and per ``(dst, src)`` of ``passes`` row ``src[m]`` of ``weight`` viewed
    ``(N*K*C_in, C_out)`` added to row ``dst[m]`` of the rectangles viewed
    ``(size / C_out, C_out)`` (two neighbours that copy one coarse node share a row: their
    weights add up, one per pass); ``back`` the rectangle row of every weight row,
    ``unused`` the weight rows no rectangle reads (padding slots)."""

    plan: blocks.BlockPlan
    passes: tuple[tuple[torch.Tensor, torch.Tensor], ...]
    back: torch.Tensor
    unused: torch.Tensor


class SkeletalLinear(nn.Module):
    """Linear map on per-node features where node i only reads its graph neighbours.

    Each node has its own weights over the features of its neighbours (a masked dense
    matrix would store mostly zeros). Input ``(B, N, C_in)``, output ``(B, N, C_out)``."""

    # buffers (register_buffer in __init__), declared for the type checker
    gather: torch.Tensor

    def __init__(self, node_mask: np.ndarray, c_in: int, c_out: int):
        super().__init__()
        n = node_mask.shape[0]
        self.n, self.c_in, self.c_out = n, c_in, c_out
        self.neigh = [np.nonzero(node_mask[i])[0].tolist() for i in range(n)]
        k = max(len(v) for v in self.neigh)
        # one-hot gather matrix (N*K, N): a matmul's backward is a deterministic product,
        # where indexing's backward accumulates in an order that varies between threads
        gather = torch.zeros(n * k, n)
        for i, v in enumerate(self.neigh):
            for slot, j in enumerate(v):
                gather[i * k + slot, j] = 1.0
        self.register_buffer("gather", gather, persistent=False)  # structure, rebuilt from the skeleton
        self.k = k
        self._layouts: dict[tuple, Layout] = {}
        self._reuse: dict[tuple, torch.Tensor] | None = None
        self.weight = nn.Parameter(torch.empty(n, k * c_in, c_out))
        self.bias = nn.Parameter(torch.zeros(n, c_out))
        for i, v in enumerate(self.neigh):
            bound = 1.0 / np.sqrt(len(v) * c_in)
            nn.init.uniform_(self.weight[i], -bound, bound)
            with torch.no_grad():
                self.weight[i, len(v) * c_in :] = 0.0  # padding slots read zeros anyway

    def _load_from_state_dict(self, state_dict, prefix, *args, **kwargs):
        # weights files from before the gather matrix stored an index buffer; it is structure
        state_dict.pop(prefix + "index", None)
        super()._load_from_state_dict(state_dict, prefix, *args, **kwargs)

    def layout(self, source: tuple[int, ...] | None, device: torch.device) -> Layout:
        """The layer's block-sparse matrix for input nodes ``source`` (see :meth:`forward`)."""
        key = (source, str(device))
        if key not in self._layouts:
            n, k, c_in, c_out = self.n, self.k, self.c_in, self.c_out
            of = list(range(n)) if source is None else list(source)
            reads = [sorted({of[j] for j in v}) for v in self.neigh]
            nodes = blocks.plan_rectangles(reads, c_out, c_in, BLOCK_CALL_COST)
            plan = blocks.BlockPlan.of(
                [(a * c_out, b * c_out, h0 * c_in, h1 * c_in) for a, b, h0, h1 in nodes],
                (max(of) + 1) * c_in,
                n * c_out,
            )
            dst: list[np.ndarray] = []
            src: list[np.ndarray] = []
            channels = np.arange(c_in)
            for (a, b, h0, h1), (_, _, _, _, offset) in zip(nodes, plan.spans):
                base, r = offset // c_out, b - a
                for i in range(a, b):
                    for slot, j in enumerate(self.neigh[i]):
                        if h0 <= of[j] < h1:
                            dst.append(base + ((of[j] - h0) * c_in + channels) * r + (i - a))
                            src.append((i * k + slot) * c_in + channels)
            d, s_ = np.concatenate(dst), np.concatenate(src)
            back = np.zeros(n * k * c_in, dtype=np.int64)
            back[s_] = d
            unused = np.setdiff1d(np.arange(n * k * c_in), s_)
            # pass m adds every rectangle row's m-th weight row: no pass names a row twice
            rank = np.empty(len(d), dtype=np.int64)
            seen: dict[int, int] = {}
            for m, r in enumerate(d.tolist()):
                rank[m] = seen.get(r, 0)
                seen[r] = rank[m] + 1
            ts = lambda a: torch.as_tensor(a, dtype=torch.long, device=device)  # noqa: E731
            passes = tuple((ts(d[rank == m]), ts(s_[rank == m])) for m in range(int(rank.max()) + 1))
            self._layouts[key] = Layout(plan, passes, ts(back), ts(unused))
        return self._layouts[key]

    def rectangles(self, source: tuple[int, ...] | None, device: torch.device) -> tuple[Layout, torch.Tensor]:
        """The layout for ``source`` and the weights in its rectangles, flat (made once per
        :func:`reusing_rectangles` block, or per call)."""
        layout = self.layout(source, device)
        key = (source, str(device), torch.is_grad_enabled())
        if self._reuse is not None and key in self._reuse:
            return layout, self._reuse[key]
        c_out = self.c_out
        rows = self.weight.reshape(-1, c_out)
        w = blocks.scatter_rows(rows, layout.passes, layout.back, layout.unused, layout.plan.size // c_out).reshape(-1)
        if self._reuse is not None:
            self._reuse[key] = w
        return layout, w

    def forward(self, x: torch.Tensor, source: tuple[int, ...] | None = None) -> torch.Tensor:
        """``(B, N_in, C_in) -> (B, N, C_out)``. ``source``: node ``j`` of the layer reads
        input node ``source[j]`` (an unpooling copy, read in place instead of made; the
        same sums); None: ``x`` has the layer's own nodes.

        A batch of :data:`BLOCKS_FROM` poses or more runs as a few dense products over
        the rectangles of the masked matrix (:mod:`engine.models.blocks`; an unpooling
        folded in reads the coarse nodes, fewer of them); a few poses keep the per-node
        products."""
        b = x.shape[0]
        if b >= BLOCKS_FROM:
            layout, w = self.rectangles(source, x.device)
            y = blocks.product(x.reshape(b, -1).contiguous(), w, self.bias.reshape(-1), layout.plan)
            return y.reshape(b, self.n, self.c_out)
        if source is not None:
            x = x.index_select(1, torch.as_tensor(source, device=x.device))
        gathered = torch.matmul(self.gather, x).reshape(b, self.n, self.k * self.c_in)  # (B, N, K*C)
        y = torch.bmm(gathered.transpose(0, 1), self.weight).transpose(0, 1)  # (B, N, C_out)
        return y + self.bias


@contextmanager
def reusing_rectangles(module: nn.Module) -> Iterator[None]:
    """Within the block, every :class:`SkeletalLinear` of ``module`` lays out its weights
    in its rectangles once and reuses them (a decoder run twice per training step, as
    the VAE's continuity loss does, then makes them, and takes their gradient, once).
    The weights must not change inside the block."""
    layers = [m for m in module.modules() if isinstance(m, SkeletalLinear)]
    for layer in layers:
        layer._reuse = {}
    try:
        yield
    finally:
        for layer in layers:
            layer._reuse = None


def pool_matrix(groups: tuple[tuple[int, ...], ...], n_in: int) -> torch.Tensor:
    """(n_out, n_in) averaging matrix for one pooling step."""
    m = torch.zeros(len(groups), n_in)
    for g, members in enumerate(groups):
        m[g, list(members)] = 1.0 / len(members)
    return m


def unpool_matrix(groups: tuple[tuple[int, ...], ...], n_in: int) -> torch.Tensor:
    """(n_in, n_out) copying matrix, the reverse of :func:`pool_matrix`."""
    m = torch.zeros(n_in, len(groups))
    for g, members in enumerate(groups):
        m[list(members), g] = 1.0
    return m


def level_sizes() -> list[int]:
    return [sk.NUM_JOINTS] + [len(g) for g in POOL_GROUPS]
