"""When to start the solver again after it died, and when to stop trying.

The studio solves in a process of its own (:mod:`engine.studio.process`). When that
process dies (out of memory, a native fault, a kill) the window starts a new one with
the whole session (:meth:`engine.studio.session.Session.restart_engine`). A process that
dies again and again (a clip or setting that crashes it at once) must not be restarted
forever: :class:`RestartPolicy` allows a restart unless this death is the
:data:`LIMIT`-th within :data:`WINDOW_S` seconds, and then says why in one line.
"""

from __future__ import annotations

import time
from collections import deque
from collections.abc import Callable

#: Deaths within :data:`WINDOW_S` after which the engine is not restarted.
LIMIT = 3
#: Seconds over which deaths are counted.
WINDOW_S = 60.0


class RestartPolicy:
    """Counts engine deaths; ``clock`` gives seconds (monotonic by default)."""

    def __init__(
        self, limit: int = LIMIT, window_s: float = WINDOW_S, clock: Callable[[], float] = time.monotonic
    ) -> None:
        self.limit, self.window_s, self._clock = limit, window_s, clock
        self._deaths: deque[float] = deque()
        self.stopped = ""  # why restarting stopped; "" while it goes on

    def died(self) -> bool:
        """Note a death now; whether to restart. After a refusal :attr:`stopped` says why
        and every later death is refused too (the user restarts the studio)."""
        now = self._clock()
        self._deaths.append(now)
        while self._deaths and now - self._deaths[0] > self.window_s:
            self._deaths.popleft()
        if not self.stopped and len(self._deaths) >= self.limit:
            self.stopped = (
                f"the solver process stopped {len(self._deaths)} times within {self.window_s:.0f} s, "
                "so it is not restarted again"
            )
        return not self.stopped
