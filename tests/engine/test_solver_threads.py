"""engine/solver/threads.py: one BLAS thread inside, the counts as before after."""

from __future__ import annotations

import pytest
from threadpoolctl import threadpool_info, threadpool_limits

from engine.solver.threads import _BLAS_LIBS, one_blas_thread


def _blas_threads() -> list[int]:
    return [i["num_threads"] for i in threadpool_info() if i["user_api"] == "blas"]


def test_one_blas_thread_inside_and_the_counts_restored_after_even_on_error():
    assert _BLAS_LIBS, "numpy's BLAS must be found"
    with threadpool_limits(limits=2, user_api="blas"):
        before = _blas_threads()
        with one_blas_thread():
            assert set(_blas_threads()) == {1}
        assert _blas_threads() == before
        with pytest.raises(RuntimeError), one_blas_thread():
            raise RuntimeError("a failing solve")
        assert _blas_threads() == before
