"""Simulated tracker failures happen once, with a countdown in the tracker's row.

A failure is a frame range on the sensor (:class:`engine.sensors.Sensor` ``failures``).
Left there, it came back on every loop of the clip. :class:`FailureCountdown` watches
the frames the window draws: while a failure covers the frame its row counts the
frames left, and once the frame has passed its end (or playback has jumped back to
before its start after it began) the range is dropped from the sensor. Dropping it is
the failure running its course, not an edit, so it makes no undo step.
"""

from __future__ import annotations

from app.shell import StudioShell


class FailureCountdown:
    """Ends the simulated failures of ``window.session`` and shows their countdown in
    ``window.sensor_panel``; call :meth:`on_frame` with every drawn frame."""

    def __init__(self, window: StudioShell) -> None:
        self.w = window
        self._started: set[tuple[str, int, int]] = set()  # failures seen covering a frame
        self._shown: dict[str, int | None] = {}

    def on_frame(self, frame: int) -> None:
        s = self.w.session
        for joint, cfg in list(s.sensors.items()):
            if not cfg.failures:
                if self._shown.get(joint) is not None:
                    self._show(joint, None)
                continue
            keep, left = [], None
            for a, b in cfg.failures:
                if a <= frame < b:
                    self._started.add((joint, a, b))
                    left = max(left or 0, b - frame)
                    keep.append((a, b))
                elif frame < a and (joint, a, b) not in self._started:
                    keep.append((a, b))  # still to come
            if len(keep) != len(cfg.failures):
                with self.w.undo.unrecorded():
                    s.sensors.edit(joint, failures=tuple(keep))
            self._show(joint, left)

    def _show(self, joint: str, left: int | None) -> None:
        if self._shown.get(joint, None) != left:
            self._shown[joint] = left
            self.w.sensor_panel.set_failure_left(joint, left)
