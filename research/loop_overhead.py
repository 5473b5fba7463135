"""What the solve loop itself costs per iteration, with the objective left out: the
frame-by-frame loop (:meth:`engine.solver.optimizer.PoseOptimizer._run`'s bookkeeping:
one latent, scalar totals, :meth:`LatentUpdate.step`) against the rows loop of
:func:`engine.solver.batch.solve_streams` run as a batch of one (index arrays, row
gathers and scatters, :meth:`LatentUpdate.step_rows`, the stopping rule on arrays).

    PYTHONPATH=. python research/loop_overhead.py [--iterations 20000]

Prints the median microseconds per iteration of each, over 7 repeats (thread CPU time).
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from engine.solver.objective import StoppingRule
from engine.solver.update import LatentUpdate

L, K = 24, 9


def single(n: int) -> float:
    z, values, weights = np.zeros(L, np.float32), np.ones(K), np.ones(K)
    grad = np.full(L, 0.01, np.float32)
    upd, stopping = LatentUpdate("adam-carry", 0.01), StoppingRule(10**9, False, 10, 1e-4)
    t = time.thread_time()
    for _ in range(n):
        total = float(weights @ values)
        _ = dict(zip(("a",) * K, values.tolist()))
        if not np.isfinite(z).all():
            break
        stopping.stop(np.array([total]), lambda: np.array([True]))
        z = upd.step(z, grad)
        stopping.stepped()
    return 1e6 * (time.thread_time() - t) / n


def rows(n: int) -> float:
    z, values, weights = np.zeros((1, L), np.float32), np.ones((1, K)), np.ones((1, K))
    grad = np.full((1, L), 0.01, np.float32)
    upd, stopping = LatentUpdate("adam-carry", 0.01), StoppingRule(10**9, False, 10, 1e-4, rows=1)
    live = [0]
    t = time.thread_time()
    for _ in range(n):
        idx = np.array(live, dtype=np.intp)
        zi = z[idx]
        total = (weights[idx] * values).sum(1)
        stop = stopping.stop(total, lambda: np.ones(1, bool), idx)
        if not stop.all():
            keep = ~stop
            upd.step_rows(z, (grad + zi * 0)[keep], idx[keep])
            stopping.stepped(idx[keep])
    return 1e6 * (time.thread_time() - t) / n


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--iterations", type=int, default=20000)
    a = ap.parse_args()
    for name, f in (("frame-by-frame loop", single), ("rows loop, one row", rows)):
        print(f"{name:<22} {np.median([f(a.iterations) for _ in range(7)]):6.1f} us per iteration")


if __name__ == "__main__":
    main()
