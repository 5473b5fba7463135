"""A notice while the engine loads a model and solves its first frame.

Loading DragPoser's networks and solving the first frame offline takes seconds on a
laptop CPU; without a word the studio looks frozen. The notice shows in the 3D view and
the status bar from the moment a clip or method is requested until the engine
publishes a frame solved by that method.
"""

from __future__ import annotations

from typing import Any

from PyQt6.QtWidgets import QStatusBar


class BusyNotice:
    """Show ``text`` until :meth:`check` sees a newer snapshot from the awaited method.

    Parameters
    ----------
    viewport : widgets.viewport.Viewport
        Shows the notice over the 3D view (``set_notice``).
    status : QStatusBar
        Also shows it, for screen readers and when the view is hidden.
    """

    def __init__(self, viewport: Any, status: QStatusBar) -> None:
        self.viewport, self.status = viewport, status
        self.method: str | None = None
        self.after_seq = -1
        self.text = ""

    @property
    def active(self) -> bool:
        return self.method is not None

    def begin(self, method: str, after_seq: int, what: str = "") -> None:
        """Wait for a snapshot from ``method`` with ``seq > after_seq``."""
        self.method, self.after_seq = method, after_seq
        # two short lines: one long line is wider than the view and cut at both ends
        self.text = f"{what or 'Loading'} {method}:\nloading the model and solving the first frame..."
        self.viewport.set_notice(self.text)
        self.status.showMessage(self.text.replace("\n", " "))

    def check(self, snap: Any) -> None:
        """Clear the notice once ``snap`` is the awaited method's (or reports its failure)."""
        if self.method is None or snap is None or snap.seq <= self.after_seq:
            return
        if snap.method == self.method or getattr(snap, "method_error", ""):
            self.end()

    def end(self) -> None:
        """Take the notice down: what it waited for came, or will never come (the engine
        refused the method, maybe in a snapshot published before :meth:`begin` read its
        ``after_seq``)."""
        self.method = None
        self.viewport.set_notice("")
        if self.status.currentMessage() == self.text.replace("\n", " "):
            self.status.clearMessage()
