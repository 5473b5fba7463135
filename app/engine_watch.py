"""The solver process dying while the studio runs: say so, start it again, or say why not.

The window checks its engine on every display tick (:class:`app.drawing.DrawScheduler`).
When the engine reports a failure (its process died: out of memory, a native fault, a
kill), the status bar says so in one line and a new engine is started with the whole
session (:meth:`engine.studio.session.Session.restart_engine`: the same clip, method,
sensors, constraints, settings, frame and playback), with the loading notice until its
first frame. The third death within a minute (:class:`engine.studio.restarts.RestartPolicy`)
is not restarted: the status bar and a message say why.
"""

from __future__ import annotations

from typing import Any

from engine.studio.restarts import RestartPolicy

#: How long the one-line status of a restart stays, milliseconds.
SHOWN_MS = 30000


class EngineWatch:
    """Watches ``window``'s engine (see the module doc); ``policy`` decides on restarts."""

    def __init__(self, window: Any, policy: RestartPolicy | None = None) -> None:
        self.w = window
        self.policy = policy or RestartPolicy()
        self.restarts = 0
        self.line = ""  # the last thing said about the engine
        self._handled: Any = None  # the dead engine last dealt with
        self._given_up: Any = None  # the dead engine not restarted

    @property
    def stopped(self) -> bool:
        """The session's engine died and was not restarted: what it last published is
        stale, and the status bar keeps saying why it stopped."""
        return self._given_up is not None and self._given_up is self.w.session.engine

    def check(self) -> None:
        """Deal with a dead engine once (cheap when it runs)."""
        session = self.w.session
        engine = session.engine
        failure = getattr(engine, "failure", "") if engine is not None else ""
        if not failure or engine is self._handled:
            return
        self._handled = engine
        if self.policy.died():
            session.restart_engine()
            self.restarts += 1
            self.line = (
                f"The solver stopped ({failure}); restarted it on frame {session.frame} with the same "
                "clip, method, sensors and constraints"
            )
            self.w.busy.begin(session.method, -1, "Restarting")
            self.w.statusBar().showMessage(self.line, SHOWN_MS)
            return
        self._given_up = engine
        self.line = f"The solver stopped ({failure}): {self.policy.stopped}"
        self.w.statusBar().showMessage(self.line)
        self.w.show_error(
            "The engine stopped",
            f"{self.line}.\n\nYour edits are kept: save the scene (File > Save scene) and start the studio again.",
        )
