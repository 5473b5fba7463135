"""The engine loop in a process of its own: the same commands in, the same snapshots out.

:class:`EngineProcess` has the interface of :class:`~engine.studio.thread.EngineThread`
(``start``, ``submit``, ``stop``, ``is_alive``, ``latest``, ``listeners``) but runs the
loop in a child process, so the solver's Python (many small numpy and torch calls) and
the window's drawing never wait for each other's global interpreter lock: on two cores
each gets one. Commands travel through a ``multiprocessing`` queue (pickled: clips,
frozen sensors, constraint objects); snapshots come back through a pipe, and a small
receiver thread here keeps the newest one in :attr:`EngineProcess.latest`.

A snapshot's ``history`` (up to :data:`~engine.studio.snapshot.HISTORY` frame records)
is sent as the records added since the previous snapshot; the receiver rebuilds the
whole tuple, so readers see exactly what the thread would give them.

The child is started with ``spawn`` (no copy of the window's Qt, VTK or X11 state),
exits when the window's process does (it watches its parent), and is terminated if it
does not stop within the timeout of :meth:`EngineProcess.stop`. A child that dies is
reported in :attr:`EngineProcess.failure`.
"""

from __future__ import annotations

import dataclasses
import gc
import multiprocessing as mp
import os
import pickle
import sys
import threading
from collections import deque
from collections.abc import Callable
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:  # imported when first used: `gui` starts this process before the engine's imports (app.cli)
    from engine.studio.commands import Command

#: How often the child checks that the window's process is still there, seconds.
PARENT_POLL_S = 1.0


class EngineProcess:
    """Runs :class:`~engine.studio.thread.EngineThread`'s loop in a child process.

    Parameters
    ----------
    method_factory : callable, optional
        ``factory(name) -> Method``, picklable (a module-level function); the engine's
        :func:`~engine.studio.method_edits.make_method` by default.
    threads : int, optional
        Math-library threads of the child (OpenMP, BLAS, torch); default: all cores but
        one, which the window keeps for drawing.
    prepare : str
        A method the child builds as soon as it has started, before reading any command
        (:meth:`~engine.studio.thread.EngineThread.prepare`): the window's first
        selection of it then finds its models loaded. "" builds nothing ahead.
    """

    def __init__(
        self, method_factory: Callable[[str], Any] | None = None, threads: int | None = None, prepare: str = ""
    ) -> None:
        ctx = mp.get_context("spawn")
        self._commands = ctx.Queue()
        self._receive, send = ctx.Pipe(duplex=False)
        n = threads if threads is not None else max(1, (os.cpu_count() or 2) - 1)
        self._process = ctx.Process(
            target=_child_main,
            args=(self._commands, send, method_factory, n, os.getpid(), prepare),
            name="dragposer-engine",
            daemon=True,
        )
        self._send_end = send
        self._receiver = threading.Thread(target=self._receive_loop, name="dragposer-engine-receiver", daemon=True)
        self.latest: Any = None
        self.listeners: list[Callable[[Any], None]] = []
        #: Why the child stopped on its own ("" while it runs or after a requested stop).
        self.failure = ""
        self._stopping = False
        self._history: deque = deque()

    # -- the EngineThread interface -----------------------------------------------------
    def start(self) -> None:
        self._process.start()
        self._send_end.close()  # the child holds the only sending end: EOF when it exits
        self._receiver.start()

    def submit(self, command: Command) -> None:
        """Queue a command (pickled on the queue's feeder thread); returns at once.

        Raises
        ------
        TypeError
            For anything but an :class:`engine.studio.commands.Command` (the child's
            engine thread dispatches on the command's class).
        """
        from engine.studio.commands import Command

        if not isinstance(command, Command):
            raise TypeError(f"the engine takes commands (engine.studio.commands), not {type(command).__name__!r}")
        self._commands.put(command)

    @staticmethod
    def can_send(command: Any) -> bool:
        """Whether ``command`` can cross to the child (a live tracker source, with its
        socket and threads, cannot; the session then runs the engine in a thread)."""
        try:
            pickle.dumps(command)
        except Exception:  # anything pickle refuses: sockets, locks, lambdas
            return False
        return True

    def is_alive(self) -> bool:
        return self._process.is_alive() or self._receiver.is_alive()

    def stop(self, timeout: float = 3.0) -> None:
        """Ask the child to finish, wait up to ``timeout`` s, then terminate it."""
        from engine.studio import commands as cmd

        self._stopping = True
        if self._process.pid is None:  # never started
            return
        if self._process.is_alive():
            self._commands.put(cmd.Stop())
            self._process.join(timeout)
        if self._process.is_alive():
            self._process.terminate()
            self._process.join(1.0)
        if self._process.is_alive():
            self._process.kill()
            self._process.join(1.0)
        self._receiver.join(timeout)
        # the child is gone: commands still in the pipe have no reader (and this process
        # holds the pipe's other end), so waiting for the queue's feeder could block forever
        self._commands.cancel_join_thread()
        self._commands.close()

    # -- receiving --------------------------------------------------------------------
    def _receive_loop(self) -> None:
        while True:
            try:
                message = self._receive.recv()
            except (EOFError, OSError):
                break
            except Exception as exc:  # a message cut short by a dying child
                self.failure = f"the engine process sent a broken snapshot: {exc}"
                break
            if message is None:  # the child's last word after a Stop
                break
            snap = self._rebuild(*message)
            self.latest = snap
            for cb in list(self.listeners):
                cb(snap)
        self._receive.close()
        if not self._stopping and not self.failure:
            self._process.join(1.0)
            self.failure = f"the engine process stopped unexpectedly (exit code {self._process.exitcode})"

    def _rebuild(self, snap: Any, new_records: tuple, reset: bool) -> Any:
        from engine.studio.snapshot import HISTORY

        if reset:
            self._history = deque(maxlen=HISTORY)
        for record in new_records:
            _freeze(record.latent)
        self._history.extend(new_records)
        for f in dataclasses.fields(snap):  # unpickled arrays are writeable again
            value = getattr(snap, f.name)
            for a in value.values() if isinstance(value, dict) else (value,):
                _freeze(a)
        return dataclasses.replace(snap, history=tuple(self._history))


def _freeze(a: Any) -> None:
    if hasattr(a, "flags"):
        a.flags.writeable = False


class HistorySender:
    """The child's snapshot listener: sends each snapshot with only its new history."""

    def __init__(self, conn: Any) -> None:
        self.conn = conn
        self._last: Any = None  # the newest record sent

    def __call__(self, snap: Any) -> None:
        history = snap.history
        start = None
        if self._last is not None:
            for i in range(len(history) - 1, -1, -1):
                if history[i] is self._last:
                    start = i + 1
                    break
        reset = start is None
        new = history if reset else history[start:]
        self._last = history[-1] if history else None
        try:
            self.conn.send((dataclasses.replace(snap, history=()), tuple(new), reset))
        except (BrokenPipeError, ConnectionResetError):
            # the window's end of the pipe is closed (its process was killed or is
            # quitting): nobody reads this solver's frames, so it ends without a traceback
            os._exit(0)


def _watch_parent(parent: int) -> None:
    """End this process when the window's process is gone (no orphan solver)."""
    import time

    while True:
        time.sleep(PARENT_POLL_S)
        if os.getppid() != parent:
            os._exit(0)


def _child_main(commands: Any, conn: Any, method_factory: Any, threads: int, parent: int, prepare: str = "") -> None:
    from engine.startup_trace import mark

    mark("engine process up")
    # no cyclic collections while the imports and the models' loading create their
    # long-lived objects (collections that free nothing); frozen once the method is ready
    gc.disable()
    for var in ("OMP_NUM_THREADS", "MKL_NUM_THREADS", "OPENBLAS_NUM_THREADS"):
        os.environ[var] = str(threads)
    threading.Thread(target=_watch_parent, args=(parent,), daemon=True).start()
    import torch

    torch.set_num_threads(threads)
    mark("engine: torch imported")
    from engine.studio.thread import EngineThread

    engine = EngineThread(method_factory, commands=commands)
    engine.listeners.append(HistorySender(conn))
    if prepare:
        engine.prepare(prepare)
    gc.freeze()
    gc.enable()
    try:
        engine.run()  # this process's main thread runs the loop
    finally:
        try:
            conn.send(None)
        except (OSError, ValueError):
            pass
        conn.close()
    # a requested stop: nothing is left to write, so skip the interpreter's teardown (torch's
    # modules and threads: about a second of the window's close on a busy machine, which
    # waits for this process to end); a failing loop raised above and exits as usual
    sys.stdout.flush()
    sys.stderr.flush()
    os._exit(0)
