"""How ``evaluate`` and ``reconstruct`` run their per-file jobs; results are merged in file order.

* ``--jobs N`` (the default executor, ``local``): one worker process per input file.
  Each worker runs one torch thread and one BLAS thread (the per-frame solve is a chain
  of tiny operations that gains nothing from more, and the workers would only compete),
  and builds its method once. Workers are started with ``spawn`` so they inherit no
  threads or locks from the parent. ``--jobs 1`` (or a single file) runs in this process.
* ``--executor ray [--address ADDR]``: the same jobs as Ray tasks (one CPU each, one
  thread each as above), on the cluster at ``ADDR`` or, without it, on a Ray instance
  started for the run on this machine and stopped after it (or the one this process
  has already started). Ray is an optional extra (``pip install '.[cluster]'``); every
  node needs this package installed and the input and output paths visible under the
  same names (docs/performance.md, "A folder of clips on a cluster").

This module is the only place that dispatches jobs.
"""

from __future__ import annotations

import argparse
import os
from collections.abc import Callable, Sequence
from concurrent.futures import ProcessPoolExecutor, as_completed
from dataclasses import dataclass
from multiprocessing import get_context
from typing import Any, TypeVar

from engine.errors import UserError

T = TypeVar("T")


#: ``--executor`` choices.
EXECUTORS = ("local", "ray")


@dataclass(frozen=True)
class Executor:
    """Where jobs run: ``kind`` ``local`` (``--jobs`` processes) or ``ray``; ``address``
    the Ray cluster's (None: a local instance)."""

    kind: str = "local"
    address: str | None = None


LOCAL = Executor()


def add_jobs_option(p: argparse.ArgumentParser) -> None:
    p.add_argument(
        "--jobs",
        type=int,
        metavar="N",
        default=None,
        help="worker processes, one file at a time each (default: the number of cores; 1: no workers)",
    )
    p.add_argument(
        "--executor",
        choices=EXECUTORS,
        default="local",
        help="local: --jobs worker processes; ray: Ray tasks, one per file (needs the 'cluster' extra)",
    )
    p.add_argument(
        "--address",
        metavar="ADDR",
        default=None,
        help="with --executor ray: the Ray cluster to run on (default: a local Ray instance for this run)",
    )


def executor_of(args: argparse.Namespace) -> Executor:
    """The ``--executor`` / ``--address`` choice; a :class:`UserError` for ``--address``
    without ``--executor ray`` or ``ray`` without Ray installed."""
    kind, address = getattr(args, "executor", "local"), getattr(args, "address", None)
    if kind == "local":
        if address is not None:
            raise UserError("--address applies to --executor ray")
        return LOCAL
    try:
        import ray  # noqa: F401
    except ImportError:
        raise UserError("--executor ray needs Ray: pip install 'dragposer-studio[cluster]'") from None
    return Executor("ray", address)


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


def map_files(
    fn: Callable[[Any], T],
    items: Sequence[Any],
    jobs: int,
    progress: bool = True,
    desc: str = "files",
    executor: Executor = LOCAL,
) -> list[T]:
    """``[fn(x) for x in items]``, in worker processes when ``jobs > 1`` and there are
    several items, or as Ray tasks with a ``ray`` ``executor`` (``fn`` must be a
    module-level function; its :class:`UserError` is re-raised here)."""
    if executor.kind == "ray":
        return _map_ray(fn, items, executor.address, progress, desc)
    if jobs <= 1 or len(items) <= 1:
        return [fn(x) for x in items]
    from tqdm import tqdm

    with ProcessPoolExecutor(
        max_workers=min(jobs, len(items)), mp_context=get_context("spawn"), initializer=_one_thread
    ) as pool:
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


def _map_ray(fn: Callable[[Any], T], items: Sequence[Any], address: str | None, progress: bool, desc: str) -> list[T]:
    import ray
    from tqdm import tqdm

    started = not ray.is_initialized()
    if started:  # workers inherit this process's environment (PYTHONPATH) on a local instance
        ray.init(address=address, include_dashboard=False, log_to_driver=False, configure_logging=False)
    try:
        task = ray.remote(num_cpus=1)(_ray_call)
        refs = [task.remote(fn, x) for x in items]
        pending = list(refs)
        with tqdm(total=len(refs), desc=desc, unit="file", disable=not progress) as bar:
            while pending:
                ready, pending = ray.wait(pending, num_returns=1)
                bar.update(len(ready))
        out = []
        for ok, value in ray.get(refs):  # file order
            if not ok:
                raise UserError(value)
            out.append(value)
        return out
    finally:
        if started:
            ray.shutdown()


def _ray_call(fn: Callable[[Any], T], x: Any) -> tuple[bool, Any]:
    _one_thread()
    return _call(fn, x)


def _call(fn: Callable[[Any], T], x: Any) -> tuple[bool, Any]:
    try:
        return True, fn(x)
    except UserError as exc:
        return False, str(exc)
