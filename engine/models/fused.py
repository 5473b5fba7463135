"""The pose decoder as a few block-sparse layers, with its input gradient derived by hand.

Every stage of :meth:`engine.models.vae.PoseVAE.decode` between two activations is
affine: an unpooling copy followed by a skeletal linear layer (a gather and per-node
weights). Each such stage is therefore exactly one matrix and bias, read off by feeding
the stage the unit vectors (in float64, then stored in float32 like the model). The
decoder becomes six matrix-vector products with LeakyReLU in between, and its gradient
with respect to the latent is the same products transposed, which is what the solver
needs per iteration; no autograd graph, no per-node gathers.

Those matrices are mostly zeros (a node only reads its neighbours in the joint graph):
of 1.77 M entries only 0.64 M are not. What costs time per iteration is reading the
weights (twice: forward and backward), so each matrix is stored as a few dense
rectangles: consecutive output nodes are grouped into *runs*, each run keeps only the
contiguous range of input columns its nodes read, and a run is one BLAS product on
slices (no gather, no copy). The grouping minimises ``entries stored + CALL_COST per
run`` by dynamic programming over the node order (:func:`plan_runs`). Entries outside
every rectangle are exactly zero in the dense matrix, so the products are the same sums.

The backward pass reads the same rectangles transposed (``g[r0:r1] @ w``, added into the
input gradient's columns ``c0:c1``): one copy of the weights, 3.6 MB, serves both passes,
which keeps them in a core's L2 cache between the forward and the backward (two copies,
7.3 MB, spilled to L3: see docs/performance.md).

The same products take many latents at once as columns (:meth:`DenseDecoder.columns`: the
batched offline solve, :mod:`engine.solver.batch`): each rectangle is then one
matrix-matrix product, the weights read once for all the columns.

The last stage folds in the quaternion identity bias and the displacement's
de-normalisation, so its output is ``(q_raw (22*4), disp (3))`` in metres.
"""

from __future__ import annotations

import copy
from dataclasses import dataclass

import numpy as np
import torch

from engine.models.skeletal import level_sizes

#: Cost of one more BLAS call in the run planner, in weight entries (about the
#: entries one call's overhead could have read; measured, see docs/performance.md).
CALL_COST = 8000


@dataclass(frozen=True)
class Run:
    """One dense rectangle of a block-sparse matrix: ``y[r0:r1] = w @ x[c0:c1]``."""

    r0: int
    r1: int
    c0: int
    c1: int
    w: np.ndarray  # (r1 - r0, c1 - c0) float32, C-contiguous


def plan_runs(
    w: np.ndarray, rows: list[tuple[int, int]], cols: list[tuple[int, int]], call_cost: float = CALL_COST
) -> list[Run]:
    """Cover the non-zero node blocks of ``w (out, in)`` by row runs (module doc).

    Parameters
    ----------
    w : ndarray (out, in)
    rows, cols : list of (start, stop)
        Consecutive node partitions of the rows and the columns.
    call_cost : float
        Entries one more run must save to be worth its call.

    Returns
    -------
    list of Run
        Disjoint row ranges covering every row, in order.
    """
    mask = np.array([[np.any(w[r0:r1, c0:c1] != 0) for c0, c1 in cols] for r0, r1 in rows])
    n = len(rows)
    best, start = [0.0] + [np.inf] * n, [0] * (n + 1)

    def span(s: int, e: int) -> tuple[int, int]:
        used = np.nonzero(mask[s:e].any(0))[0]
        if len(used) == 0:  # rows that read nothing: an empty product
            return 0, 0
        return cols[used[0]][0], cols[used[-1]][1]

    for e in range(1, n + 1):
        for s in range(e):
            c0, c1 = span(s, e)
            cost = best[s] + (rows[e - 1][1] - rows[s][0]) * (c1 - c0) + call_cost
            if cost < best[e]:
                best[e], start[e] = cost, s
    runs, e = [], n
    while e > 0:
        s = start[e]
        (r0, r1), (c0, c1) = (rows[s][0], rows[e - 1][1]), span(s, e)
        runs.append(Run(r0, r1, c0, c1, np.ascontiguousarray(w[r0:r1, c0:c1], dtype=np.float32)))
        e = s
    return runs[::-1]


def _nodes(count: int, width: int, start: int = 0) -> list[tuple[int, int]]:
    return [(start + i * width, start + (i + 1) * width) for i in range(count)]


class DenseDecoder:
    """Gradient-aware copy of a :class:`PoseVAE` decoder (numpy, one latent at a time, or
    a fixed number of them as columns: :meth:`columns`), its matrices stored block-sparse
    (module doc).

    Parameters
    ----------
    vae : PoseVAE
        Source model (not modified).

    Attributes
    ----------
    weights : list of ndarray (out, in), float32
        The dense stage matrices (the exact reference; not used per iteration).
    biases : list of ndarray (out,), float32
    forward_runs : list of list of Run
        Per stage, the rectangles of the matrix (both passes read them).
    slope : float
        LeakyReLU negative slope (after every stage but the last).
    """

    def __init__(self, vae, call_cost: float = CALL_COST) -> None:
        m = copy.deepcopy(vae).double().eval()
        n = level_sizes()
        ch = m.config.channels
        ident = torch.tensor([1.0, 0.0, 0.0, 0.0], dtype=torch.float64)

        def last(x):
            x = x.reshape(-1, n[0], ch[0])
            q = (m.to_rot(x) + ident).flatten(1)
            disp = m.to_disp(x[:, 0]) * m.disp_std + m.disp_mean
            return torch.cat((q, disp), dim=1)

        stages = [
            (m.config.latent, lambda x: m.from_latent(x)),
            (n[3] * ch[3], lambda x: m.dec[0](torch.matmul(m.unpool2, x.reshape(-1, n[3], ch[3]))).flatten(1)),
            (n[2] * ch[2], lambda x: m.dec[1](torch.matmul(m.unpool1, x.reshape(-1, n[2], ch[2]))).flatten(1)),
            (n[1] * ch[1], lambda x: m.dec[2](torch.matmul(m.unpool0, x.reshape(-1, n[1], ch[1]))).flatten(1)),
            (n[0] * ch[0], lambda x: m.dec[3](x.reshape(-1, n[0], ch[0])).flatten(1)),
            (n[0] * ch[0], last),
        ]
        # node partitions of each stage's input and output (the latent is one node)
        parts = [
            [(0, m.config.latent)],
            _nodes(n[3], ch[3]),
            _nodes(n[2], ch[2]),
            _nodes(n[1], ch[1]),
            _nodes(n[0], ch[0]),
            _nodes(n[0], ch[0]),
            _nodes(n[0], 4) + [(4 * n[0], 4 * n[0] + 3)],
        ]
        self.weights, self.biases = [], []
        with torch.no_grad():
            for size, f in stages:
                eye = torch.eye(size, dtype=torch.float64)
                bias = f(torch.zeros(1, size, dtype=torch.float64))[0]
                w = (f(eye) - bias).T  # (out, in)
                self.weights.append(np.ascontiguousarray(w.numpy(), dtype=np.float32))
                self.biases.append(bias.numpy().astype(np.float32))
        self.forward_runs = [plan_runs(w, parts[i + 1], parts[i], call_cost) for i, w in enumerate(self.weights)]
        self.slope = float(m.config.negative_slope)
        self.latent = int(m.config.latent)
        self._allocate()

    def _allocate(self, width: int | None = None) -> None:
        # Fixed buffers, and every product's operands as views into them, made once: a
        # product is then one BLAS call with no slicing or allocation per iteration.
        # ``width`` latents as columns: every buffer gets that many columns.
        f32 = np.float32
        cols = () if width is None else (width,)
        self.width: int | None = width
        self._twin: DenseDecoder | None = None
        self._z = np.empty((self.latent, *cols), f32)
        self._bias = [b if width is None else b[:, None] for b in self.biases]
        self._pre = [np.empty((w.shape[0], *cols), f32) for w in self.weights]  # pre-activations
        self._act = [np.empty((w.shape[0], *cols), f32) for w in self.weights[:-1]]
        self._gate = [np.empty((w.shape[0], *cols), f32) for w in self.weights[:-1]]  # LeakyReLU slopes
        self._gin = [np.empty((w.shape[0], *cols), f32) for w in self.weights]  # gradient at a stage's output
        self._grad = [np.empty((w.shape[1], *cols), f32) for w in self.weights]  # ... and at its input
        inputs = [self._z] + self._act
        self._fwd = [_bind(runs, inputs[i], self._pre[i]) for i, runs in enumerate(self.forward_runs)]
        self._bwd = [_bind_transposed(runs, self._gin[i], self._grad[i]) for i, runs in enumerate(self.forward_runs)]

    def with_own_buffers(self) -> "DenseDecoder":
        """A decoder that shares this one's matrices and runs (read only) and has scratch
        buffers of its own (a few kB, made in well under a millisecond). A :meth:`backward`
        reads the activation slopes its :meth:`forward` left in the buffers, so two solvers
        on one model (the pose window and a bake on a worker thread, two methods built
        from the same loaded models) must not share them."""
        twin = copy.copy(self)
        twin._allocate(self.width)
        return twin

    def columns(self, width: int) -> "DenseDecoder":
        """A decoder sharing this one's matrices whose :meth:`forward` takes ``width``
        latents as the columns of ``z (L, width)`` and returns ``(91, width)``, and whose
        :meth:`backward` takes and returns gradients of the same shapes. Its buffers are
        made on the first call with a width and kept until a call with another."""
        twin = self._twin
        if twin is None or twin.width != width:
            twin = copy.copy(self)
            twin._allocate(width)
            self._twin = twin
        return twin

    def __deepcopy__(self, memo: dict) -> "DenseDecoder":
        """The same object: its weights are frozen and its scratch buffers are views of
        one another, which a copy would split (a copy of a method's temporal state,
        :mod:`engine.studio.method_state`, shares it like the network it came from)."""
        return self

    def stored_entries(self) -> int:
        """Weight entries read per pass, forward or backward (dense: all of them)."""
        return sum(r.w.size for runs in self.forward_runs for r in runs)

    def forward(self, z: np.ndarray) -> np.ndarray:
        """``z (L,)`` float32 -> ``(q_raw (88,), disp (3,))`` concatenated, float32 (a new
        array); with :meth:`columns`, ``z (L, width)`` -> ``(91, width)``. Remembers the
        activation slopes for the next :meth:`backward`."""
        self._z[:] = z
        dot, last, slope = np.dot, len(self.weights) - 1, np.float32(self.slope)
        for i, (products, empty) in enumerate(self._fwd):
            for w, x, y in products:
                dot(w, x, out=y)
            for y in empty:
                y[:] = 0.0
            y = self._pre[i]
            y += self._bias[i]
            if i < last:
                gate = self._gate[i]
                np.copyto(gate, slope)
                gate[y > 0] = 1.0
                np.multiply(y, gate, out=self._act[i])
        return self._pre[last].copy()

    def pre_activations(self) -> list[np.ndarray]:
        """The last :meth:`forward`'s pre-activations of the stages a LeakyReLU follows,
        one ``(units,)`` float32 copy per stage: the side of zero each lies on is the
        slope :meth:`backward` takes through that unit."""
        return [p.copy() for p in self._pre[:-1]]

    def backward(self, grad_out: np.ndarray) -> np.ndarray:
        """Gradient w.r.t. the latent ``(L,)`` of a loss whose gradient w.r.t. the last
        :meth:`forward` output is ``grad_out (91,)`` (a new array); with :meth:`columns`,
        ``(91, width)`` -> ``(L, width)``."""
        dot, last = np.dot, len(self.weights) - 1
        self._gin[last][:] = grad_out
        for i in range(last, -1, -1):
            if i < last:
                np.multiply(self._grad[i + 1], self._gate[i], out=self._gin[i])
            writes, adds, zero = self._bwd[i]
            for y in zero:
                y[:] = 0.0
            for a, b, y in writes:
                dot(a, b, out=y)
            for a, b, y, tmp in adds:
                dot(a, b, out=tmp)
                y += tmp
        return self._grad[0].copy()


def _bind(runs: list[Run], x: np.ndarray, out: np.ndarray) -> tuple[list[tuple], list[np.ndarray]]:
    """The products of ``out = W @ x`` as ``(w, x view, out view)`` triples, and the
    output views of runs that read nothing (zero)."""
    products = [(r.w, x[r.c0 : r.c1], out[r.r0 : r.r1]) for r in runs if r.c1 > r.c0]
    return products, [out[r.r0 : r.r1] for r in runs if r.c1 <= r.c0]


def _bind_transposed(
    runs: list[Run], g: np.ndarray, out: np.ndarray
) -> tuple[list[tuple], list[tuple], list[np.ndarray]]:
    """The products of ``out = W^T @ g`` over the rectangles of ``W``, each as the operands
    of one ``dot(a, b, out=...)`` (``g view, w`` for one latent, ``w.T, g view`` for
    columns): ``(a, b, out view)`` for a run whose columns no earlier run reads (written
    directly), ``(a, b, out view, scratch)`` for one that shares columns with an earlier
    run (added; every such run comes after the run it shares with, so it adds to a
    written value), and the views of the columns no direct run writes (zeroed first)."""
    written = np.zeros(len(out), dtype=bool)
    touched = np.zeros(len(out), dtype=bool)
    writes, adds = [], []
    for r in runs:
        if r.c1 <= r.c0:
            continue
        a, b = (g[r.r0 : r.r1], r.w) if g.ndim == 1 else (r.w.T, g[r.r0 : r.r1])
        if not touched[r.c0 : r.c1].any():
            writes.append((a, b, out[r.c0 : r.c1]))
            written[r.c0 : r.c1] = True
        else:
            adds.append((a, b, out[r.c0 : r.c1], np.empty(out[r.c0 : r.c1].shape, out.dtype)))
        touched[r.c0 : r.c1] = True
    edges = np.flatnonzero(np.diff(np.r_[False, ~written, False].astype(np.int8)))
    return writes, adds, [out[a:b] for a, b in zip(edges[::2], edges[1::2])]
