"""``--jobs N``: one worker process per input file, results merged in file order.

Each worker runs one torch thread and one BLAS thread (the per-frame solve is a chain of
tiny operations that gains nothing from more, and the workers would only compete), and
builds its method once. Workers are started with ``spawn`` so they inherit no threads
or locks from the parent. ``--jobs 1`` (or a single file) runs in this process.
"""

from __future__ import annotations

import argparse
import os
from collections.abc import Callable, Sequence
from concurrent.futures import ProcessPoolExecutor, as_completed
from multiprocessing import get_context
from typing import Any, TypeVar

from engine.errors import UserError

T = TypeVar("T")


def add_jobs_option(p: argparse.ArgumentParser) -> None:
    p.add_argument("--jobs", type=int, metavar="N", default=None,
                   help="worker processes, one file at a time each (default: the number of cores; 1: no workers)")  # fmt: skip


def jobs_of(args: argparse.Namespace) -> int:
    """The ``--jobs`` value, defaulted to the number of cores; a :class:`UserError` if < 1."""
    jobs = args.jobs if args.jobs is not None else (os.cpu_count() or 1)
    if jobs < 1:
        raise UserError(f"--jobs must be at least 1, got {jobs}")
    return jobs


def _one_thread() -> None:
    import torch
    from threadpoolctl import threadpool_limits

    torch.set_num_threads(1)
    threadpool_limits(limits=1)


def map_files(fn: Callable[[Any], T], items: Sequence[Any], jobs: int, progress: bool = True,
              desc: str = "files") -> list[T]:  # fmt: skip
    """``[fn(x) for x in items]``, in worker processes when ``jobs > 1`` and there are
    several items (``fn`` must be a module-level function; its errors are re-raised)."""
    if jobs <= 1 or len(items) <= 1:
        return [fn(x) for x in items]
    from tqdm import tqdm

    with ProcessPoolExecutor(max_workers=min(jobs, len(items)), mp_context=get_context("spawn"),
                             initializer=_one_thread) as pool:  # fmt: skip
        futures = [pool.submit(_call, fn, x) for x in items]
        for _ in tqdm(as_completed(futures), total=len(futures), desc=desc, unit="file", disable=not progress):
            pass
        out = []
        for f in futures:
            ok, value = f.result()
            if not ok:  # the worker's UserError, by message (its subclasses do not all pickle)
                raise UserError(value)
            out.append(value)
        return out


def _call(fn: Callable[[Any], T], x: Any) -> tuple[bool, Any]:
    try:
        return True, fn(x)
    except UserError as exc:
        return False, str(exc)
