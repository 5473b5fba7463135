"""One BLAS thread around a solve, at the cost of two C calls per library.

The per-frame solve multiplies tiny matrices, where a second BLAS thread only waits
(:mod:`engine.solver.optimizer`). ``threadpoolctl``'s ``limit`` context rebuilds its
limiter on every entry (~50 µs, a measurable share of a realtime frame's overhead);
:func:`one_blas_thread` sets and restores the same libraries' thread counts directly.
"""

from __future__ import annotations

from collections.abc import Iterator
from contextlib import contextmanager

import numpy  # noqa: F401 (loaded first: their BLAS libraries are the ones to find)
import torch  # noqa: F401
from threadpoolctl import ThreadpoolController

_CONTROLLER = ThreadpoolController()
#: The BLAS libraries loaded when this module was imported (numpy's, torch's).
_BLAS_LIBS = [c for c in _CONTROLLER.lib_controllers if c.user_api == "blas"]


@contextmanager
def one_blas_thread() -> Iterator[None]:
    """Run the body with one thread in every BLAS library, then restore each library's
    thread count as it was (also when the body raises)."""
    before = [lib.get_num_threads() for lib in _BLAS_LIBS]
    for lib, n in zip(_BLAS_LIBS, before):
        if n != 1:
            lib.set_num_threads(1)
    try:
        yield
    finally:
        for lib, n in zip(_BLAS_LIBS, before):
            if n != 1:
                lib.set_num_threads(n)
