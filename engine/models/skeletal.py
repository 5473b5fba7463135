"""Skeleton-aware building blocks: masked ("skeletal") linear layers and joint pooling.

Following SparsePoser (Ponton et al. 2023, after Aberman et al. 2020), a joint only
sees its neighbours in the joint graph (distance <= 2) through a masked weight matrix,
and the skeleton is pooled by merging consecutive joints until a primal skeleton is
left: 22 -> 14 -> 9 -> 6 nodes here (root, two legs, two arms, torso).
"""

from __future__ import annotations

import numpy as np
import torch
from torch import nn

from engine import skeleton as sk

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


#: Batch size from which :class:`SkeletalLinear` multiplies by its dense matrix.
DENSE_FROM = 64


class SkeletalLinear(nn.Module):
    """Linear map on per-node features where node i only reads its graph neighbours.

    Each node has its own weights over the features of its neighbours (a masked dense
    matrix would store mostly zeros). Input ``(B, N, C_in)``, output ``(B, N, C_out)``."""

    # buffers (register_buffer in __init__), declared for the type checker
    gather: torch.Tensor
    dense_src: torch.Tensor
    dense_row: torch.Tensor
    dense_node: torch.Tensor

    def __init__(self, node_mask: np.ndarray, c_in: int, c_out: int):
        super().__init__()
        n = node_mask.shape[0]
        self.n, self.c_in, self.c_out = n, c_in, c_out
        neigh = [np.nonzero(node_mask[i])[0].tolist() for i in range(n)]
        k = max(len(v) for v in neigh)
        # one-hot gather matrix (N*K, N): a matmul's backward is a deterministic product,
        # where indexing's backward accumulates in an order that varies between threads
        gather = torch.zeros(n * k, n)
        for i, v in enumerate(neigh):
            for slot, j in enumerate(v):
                gather[i * k + slot, j] = 1.0
        self.register_buffer("gather", gather, persistent=False)  # structure, rebuilt from the skeleton
        self.k = k
        # where each used weight row lands in the dense (N*C_in, N, C_out) matrix of a batch pass
        src: list[int] = []
        dst: list[int] = []
        node: list[int] = []
        for i, v in enumerate(neigh):
            for slot, j in enumerate(v):
                src.extend(range((i * k + slot) * c_in, (i * k + slot + 1) * c_in))
                dst.extend(range(j * c_in, (j + 1) * c_in))
                node.extend([i] * c_in)
        for name, values in (("dense_src", src), ("dense_row", dst), ("dense_node", node)):
            self.register_buffer(name, torch.tensor(values, dtype=torch.long), persistent=False)
        self.weight = nn.Parameter(torch.empty(n, k * c_in, c_out))
        self.bias = nn.Parameter(torch.zeros(n, c_out))
        for i, v in enumerate(neigh):
            bound = 1.0 / np.sqrt(len(v) * c_in)
            nn.init.uniform_(self.weight[i], -bound, bound)
            with torch.no_grad():
                self.weight[i, len(v) * c_in :] = 0.0  # padding slots read zeros anyway

    def _load_from_state_dict(self, state_dict, prefix, *args, **kwargs):
        # weights files from before the gather matrix stored an index buffer; it is structure
        state_dict.pop(prefix + "index", None)
        super()._load_from_state_dict(state_dict, prefix, *args, **kwargs)

    def dense_weight(self) -> torch.Tensor:
        """The layer as one dense matrix ``(N*C_in, N*C_out)``: zeros where the mask
        cuts a node off, each node's weights in its neighbours' rows."""
        n, c_in, c_out = self.n, self.c_in, self.c_out
        used = self.weight.reshape(n * self.k * c_in, c_out).index_select(0, self.dense_src)
        dense = used.new_zeros(n * c_in, n, c_out).index_put((self.dense_row, self.dense_node), used)
        return dense.reshape(n * c_in, n * c_out)

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        """``(B, N, C_in) -> (B, N, C_out)``. A batch of :data:`DENSE_FROM` poses or more
        runs as one dense matrix product (a few times the arithmetic of the masked
        weights, but one large GEMM instead of a per-node batch of small ones: the VAE's
        training step 1.3x less CPU time); a few poses keep the per-node products."""
        b = x.shape[0]
        if b >= DENSE_FROM:
            y = torch.addmm(self.bias.reshape(1, -1), x.reshape(b, self.n * self.c_in), self.dense_weight())
            return y.reshape(b, self.n, self.c_out)
        gathered = torch.matmul(self.gather, x).reshape(b, self.n, self.k * self.c_in)  # (B, N, K*C)
        y = torch.bmm(gathered.transpose(0, 1), self.weight).transpose(0, 1)  # (B, N, C_out)
        return y + self.bias


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
