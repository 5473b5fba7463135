"""The playback clock of the engine thread: which clip frame is due, and when.

Playback has two paces. ``"every_frame"`` (the default) solves every clip frame in
order; the clock waits for the solver, so a slow solver plays slower than real time but
the reconstruction never drifts off the trackers. ``"real_time"`` keeps the wall clock
(elapsed time x fps x speed) and skips the frames the solver missed. Either way the
clock is timed from an *origin* (a moment and the frame shown then) that the engine
thread moves on a seek, on a play request and after a reset (a new clip, a loop, a seek
back) to the first solved frame, so the slow first solve does not skip the clip's first
second.

The clock only does arithmetic on :func:`time.monotonic`; the engine thread owns the
frame, the playing flag and the methods, and acts on what :meth:`PlaybackClock.advance`
reports (a loop resets the methods, the end stops playback).
"""

from __future__ import annotations

import time
from dataclasses import dataclass

#: What :meth:`PlaybackClock.advance` reports besides the frame: nothing, a jump back to
#: frame 0 (``loop`` on) or the last frame reached (``loop`` off).
LOOPED, ENDED = "looped", "ended"


@dataclass
class PlaybackClock:
    """Times playback at ``speed`` x the clip's frame rate.

    Attributes
    ----------
    speed : float
        Multiple of real time (> 0).
    loop : bool
        Start again at frame 0 after the last frame, instead of stopping there.
    pace : str
        ``"every_frame"`` or ``"real_time"`` (see the module docstring).
    origin : tuple of (float, int)
        (seconds of :func:`time.monotonic`, frame) playback is timed from.
    """

    speed: float = 1.0
    loop: bool = True
    pace: str = "every_frame"
    origin: tuple[float, int] = (0.0, 0)

    def restart(self, frame: int) -> None:
        """Time playback from ``frame``, now."""
        self.origin = (time.monotonic(), frame)

    def rate(self, fps: float) -> float:
        """Frames per second of wall time at this speed (never 0)."""
        return max(fps * self.speed, 1e-6)

    def wait_time(self, frame: int, last_solved: int, fps: float) -> float:
        """Seconds until the frame after ``frame`` is due (0 if it is already, or if
        ``frame`` itself still needs solving in ``every_frame`` pace)."""
        if self.pace == "every_frame" and frame != last_solved:
            return 0.0  # the current frame still needs solving
        t0, f0 = self.origin
        due = t0 + (frame - f0 + 1) / self.rate(fps)
        return max(0.0, due - time.monotonic())

    def advance(self, frame: int, last_solved: int, num_frames: int, fps: float) -> tuple[int, str]:
        """The frame playback is at now, from ``frame`` (shown) and ``last_solved``.

        Returns the frame and :data:`LOOPED`, :data:`ENDED` or ``""``. In
        ``every_frame`` pace it moves at most one frame on, and only once ``frame`` is
        solved; when the solver is behind the clock, the clock waits (its origin moves).
        """
        t0, f0 = self.origin
        now = time.monotonic()
        rate = self.rate(fps)
        if self.pace == "every_frame":
            if frame != last_solved:
                return frame, ""  # a seek or reset: solve where we are first
            due = t0 + (frame + 1 - f0) / rate
            if now < due:
                return frame, ""
            f = frame + 1
            if now - due > 1.0 / rate:  # the solver is behind the clock: the clock waits
                self.origin = (now, f)
        else:
            f = f0 + int((now - t0) * rate)
        if f >= num_frames:
            if self.loop:
                self.origin = (now, 0)
                return 0, LOOPED
            return num_frames - 1, ENDED
        return f, ""


def is_jump(frame: int, last_solved: int, fps: float) -> bool:
    """Whether solving ``frame`` after ``last_solved`` (negative: nothing solved since a
    reset) is a jump: a seek backwards or more than 2 s ahead. Playback skipping a few
    frames because the solver is slower than real time is not a jump: resetting then
    would make every frame a first frame (solved offline, slower still) and the solver
    would never catch up."""
    return last_solved < 0 or frame < last_solved or frame - last_solved > 2 * fps
