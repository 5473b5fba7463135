"""Waiting for a worker thread at close, with a bound, saying what it waits for.

A Python thread still inside torch when the interpreter finalizes is unwound through
C++ and the process aborts (``terminate called without an active exception``), so a
window that closes must not leave one running: it asks the worker to stop, then joins it
with :func:`join_saying`. The worker's work in hand (one latent inspection, one settle
round) cannot be interrupted inside torch, so the wait is long enough for it; after
``say_after`` seconds one line on stderr names the thread and what it is doing, and a
second one if the bound passes with the thread still alive.
"""

from __future__ import annotations

import sys
import threading
import time
from collections.abc import Callable

#: How long closing waits for a worker's work in hand, seconds (one latent inspection
#: takes ~8 s on a loaded 2-core machine).
STOP_WAIT_S = 60.0
#: A wait longer than this says on stderr what it waits for, seconds.
SAY_AFTER_S = 1.0


def join_saying(
    thread: threading.Thread,
    doing: Callable[[], str],
    timeout: float = STOP_WAIT_S,
    say_after: float = SAY_AFTER_S,
) -> bool:
    """Join ``thread`` for at most ``timeout`` seconds; True when it ended.

    Parameters
    ----------
    thread : threading.Thread
        A worker already asked to stop.
    doing : callable
        ``doing() -> str``: what the worker is busy with (read when the wait is said).
    timeout : float
        The bound, seconds.
    say_after : float
        Seconds after which the wait is written to stderr (with ``doing()``).
    """
    if thread is threading.current_thread() or not thread.is_alive():
        return not thread.is_alive()
    t0 = time.monotonic()
    thread.join(min(say_after, timeout))
    if thread.is_alive() and timeout > say_after:
        print(f"closing: waiting up to {timeout:.3g} s for thread {thread.name!r} ({doing()})", file=sys.stderr)
        thread.join(timeout - say_after)
    if thread.is_alive():
        print(
            f"closing: thread {thread.name!r} still running after {time.monotonic() - t0:.1f} s ({doing()})",
            file=sys.stderr,
        )
        return False
    return True
