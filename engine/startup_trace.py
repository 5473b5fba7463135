"""Timestamps of the studio's start-up, for measuring where launch time goes.

With the environment variable :data:`ENV` set to a file path, :func:`mark` appends one
line ``<unix time, s> <pid> <process CPU time, s> <label>`` to that file (every process of the studio, the
window's and the engine's, writes to the same file: a spawned child inherits the
environment). Without it :func:`mark` does nothing, so the marks stay in the start-up
path at no cost. ``research/startup_breakdown.py`` launches the studio with it and prints
the breakdown (docs/performance.md).
"""

from __future__ import annotations

import os
import time

#: Environment variable naming the trace file.
ENV = "DRAGPOSER_STARTUP_TRACE"


def mark(label: str) -> None:
    """Append ``label`` with the wall-clock time, process id and CPU time to the trace
    file, when :data:`ENV` names one (a write that fails is ignored: tracing must never
    break the studio)."""
    path = os.environ.get(ENV)
    if not path:
        return
    try:
        with open(path, "a", encoding="utf-8") as fh:
            fh.write(f"{time.time():.6f} {os.getpid()} {time.process_time():.3f} {label}\n")
    except OSError:
        pass
