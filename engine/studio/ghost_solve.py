"""Ghost reconstructions solved ahead of the frames that show them, in a process of their own.

A video of a clip with ghosts (``render --ghosts ik``) needs every method's pose at
every frame. Solving them all before the first frame is drawn made the renderer wait
(2.5 s for IK on a 10 s clip); solving them in a thread of the renderer's process
shares its interpreter lock with the drawing loop (a Python thread halved the draw
rate here). :class:`GhostSolves` runs :func:`engine.studio.export.solve_frames` for
each method in a separate process (``spawn``: the drawing process holds a GL context
and threads that a fork would copy), which streams the joint positions back in
chunks; :meth:`GhostSolves.positions` hands out frame f as soon as it is solved and
waits only when the drawing has caught up with the solve.
"""

from __future__ import annotations

import multiprocessing as mp
import queue
from typing import Any

import numpy as np

from engine import skeleton as sk
from engine.errors import UserError
from engine.progress import CancelCheck, check

#: Frames per message from the solving process (one message costs ~0.1 ms; a chunk of
#: 12 frames of one method is ~6 kB).
CHUNK = 12


def _solve(motion: Any, sensors: tuple, methods: tuple[str, ...], out: Any) -> None:
    """Child process: solve every frame with each method, send positions in chunks."""
    import signal

    # Ctrl+C reaches the whole process group: the drawing process stops this one itself
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    try:
        import torch

        torch.set_num_threads(1)  # the other core draws and encodes
        from engine.motion.clip import Motion
        from engine.solver.threads import one_blas_thread
        from engine.studio.export import solve_frames

        with one_blas_thread():
            streams = [solve_frames(motion, sensors, (), {}, name) for name in methods]
            n = len(motion)
            for start in range(0, n, CHUNK):
                stop = min(n, start + CHUNK)
                chunk = []
                for stream in streams:
                    rots, roots = zip(*(next(stream) for _ in range(start, stop)))
                    part = Motion(np.array(rots), np.array(roots), motion.skeleton, motion.fps)
                    chunk.append(part.positions().astype(np.float32))
                out.put(("chunk", start, np.stack(chunk)))
        out.put(("done", len(motion), None))
    except Exception as exc:  # reported to the drawing process, which names the method
        out.put(("error", 0, f"{type(exc).__name__}: {exc}"))


class GhostSolves:
    """Each method in ``methods`` reconstructing ``motion`` from ``sensors``, solved ahead.

    Parameters
    ----------
    motion : engine.motion.clip.Motion
        The clip the trackers are simulated from.
    sensors : tuple of engine.sensors.Sensor
        The trackers (a preset's).
    methods : tuple of str
        Method names (``ik``, ``dragposer``, ...).
    """

    def __init__(self, motion: Any, sensors: tuple, methods: tuple[str, ...]) -> None:
        self.methods = tuple(methods)
        n = len(motion)
        self._positions = np.full((len(self.methods), n, sk.NUM_JOINTS, 3), np.nan, np.float32)
        self.solved = 0  # frames [0, solved) are in
        ctx = mp.get_context("spawn")
        self._queue = ctx.Queue()
        self._proc = ctx.Process(
            target=_solve, args=(motion, tuple(sensors), self.methods, self._queue), daemon=True, name="ghost-solves"
        )
        self._proc.start()

    def positions(self, frame: int, cancelled: CancelCheck | None = None) -> dict[str, np.ndarray]:
        """``{method: joint positions (J, 3)}`` at ``frame``, waiting until it is solved;
        ``cancelled()`` is asked every 0.1 s of that wait.

        Raises
        ------
        UserError
            A method failed (the message names them) or the solving process died.
        Cancelled
            ``cancelled()`` answered True while waiting.
        """
        while self.solved <= frame:
            check(cancelled)
            wait = 0.1 if cancelled is not None or not self._proc.is_alive() else 1.0
            try:
                kind, start, payload = self._queue.get(timeout=wait)
            except queue.Empty:
                if not self._proc.is_alive() and self._queue.empty():
                    raise UserError(
                        f"ghosts {', '.join(self.methods)}: the solving process ended "
                        f"(exit code {self._proc.exitcode}) at frame {self.solved}"
                    ) from None
                continue
            if kind == "error":
                raise UserError(f"ghosts {', '.join(self.methods)}: {payload}")
            if kind == "chunk":
                self._positions[:, start : start + payload.shape[1]] = payload
                self.solved = start + payload.shape[1]
            elif kind == "done":
                self.solved = start
                if self.solved <= frame:
                    raise IndexError(f"frame {frame} of a {self.solved}-frame clip")
        return {name: self._positions[i, frame] for i, name in enumerate(self.methods)}

    def all_positions(self) -> dict[str, np.ndarray]:
        """Every frame of every method, ``{method: (N, J, 3)}`` (waits for the whole solve)."""
        n = self._positions.shape[1]
        if n:
            self.positions(n - 1)
        return {name: self._positions[i] for i, name in enumerate(self.methods)}

    def close(self) -> None:
        """Stop the solving process (at once if it is still running) and free its queue."""
        if self._proc.is_alive():
            self._proc.terminate()
        self._proc.join(timeout=5)
        self._queue.close()
        self._queue.cancel_join_thread()
