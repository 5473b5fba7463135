"""Long authoring work as jobs that run on any thread: the bake of keys, a range re-solve,
a settle of the pose.

A job is a copy of what the work reads, taken on the model's thread when it starts, and
``run(progress, cancelled)``, which computes on a worker without touching any model and
returns the result (or raises :class:`engine.progress.Cancelled`). The model's
thread then applies the result as one command: the authoring model's
:meth:`~engine.authoring.session.AuthoringSession.take_bake` or
:meth:`~engine.authoring.session.AuthoringSession.take_settle`, or the studio's clip
replaced as one undo step (:mod:`app.range_actions`). ``title`` and ``label`` say what a
progress dialog shows.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

from engine.authoring.bake import Baked, bake
from engine.authoring.document import AuthoringScene
from engine.authoring.range_edit import RangeEdit, edit_range
from engine.constraints.base import Constraint
from engine.errors import UserError
from engine.motion.clip import Motion
from engine.progress import CancelCheck, Progress

if TYPE_CHECKING:
    from engine.authoring.pose_mode import PoseMode
    from engine.authoring.state import AuthoringState


@dataclass
class BakeJob:
    """The bake of ``scene`` (a copy) with the pose VAE ``vae``; ``generation`` tells the
    session whether its scene has changed since."""

    scene: AuthoringScene
    vae: Any
    generation: int = 0
    title: str = "Bake keys"

    @property
    def label(self) -> str:
        a = self.scene.animation
        return f"Solving {len(self.scene.keys)} key(s) and {a.frames} frames..."

    def run(self, progress: Progress | None = None, cancelled: CancelCheck | None = None) -> Baked:
        return bake(self.scene, self.vae, progress=progress, cancelled=cancelled)


@dataclass
class SettleJob:
    """A settle (:meth:`engine.authoring.pose_mode.PoseMode.settle`) of ``mode``, a
    detached copy of the model's pose mode (:meth:`PoseMode.detached`); ``before`` is the
    model's state when it was made, so a pose changed meanwhile is not overwritten."""

    mode: "PoseMode"
    before: "AuthoringState"
    title: str = "Settle pose"
    label: str = "Settling the pose (an offline solve of the targets)..."

    def run(self, progress: Progress | None = None, cancelled: CancelCheck | None = None) -> "PoseMode":
        """Settle the copy and return it (the model takes its pose, feet and anchor);
        ``cancelled`` is asked between the settle's rounds."""
        self.mode.settle(cancelled)
        return self.mode


@dataclass
class RangeJob:
    """A re-solve of frames ``start..end`` of ``motion`` with ``constraints``, blended
    ``blend`` frames at each end (:func:`engine.authoring.range_edit.edit_range`);
    ``vae`` None loads the shipped pose VAE on the worker."""

    motion: Motion
    start: int
    end: int
    constraints: tuple[Constraint, ...] = ()
    blend: int = 8
    vae: Any = None
    title: str = "Re-solve range"

    @property
    def label(self) -> str:
        return f"Re-solving frames {self.start}-{self.end} ({self.end - self.start + 1} frames)..."

    def run(self, progress: Progress | None = None, cancelled: CancelCheck | None = None) -> RangeEdit:
        vae = self.vae
        if vae is None:
            from engine.models import load_default_models

            vae = load_default_models().vae
        return edit_range(
            vae, self.motion, self.start, self.end, list(self.constraints), self.blend, progress, cancelled
        )


def range_job(
    motion: Motion | None,
    constraints: list[Constraint] | tuple[Constraint, ...],
    start: int,
    end: int,
    blend: int = 8,
    floor: bool = True,
    vae: Any = None,
) -> RangeJob:
    """A :class:`RangeJob` on ``motion`` with ``constraints`` and, with
    ``floor``, feet held in floor contact; a bad range is an error here, before any work."""
    from engine.constraints import FloorConstraint

    if motion is None:
        raise UserError("open a clip first")
    n = len(motion)
    if not (0 <= int(start) <= int(end) < n):
        raise UserError(f"range {start}-{end} is not within the clip's frames 0-{n - 1}")
    if blend < 0:
        raise UserError(f"blend must be >= 0 frames, got {blend}")
    chosen = [*constraints, *([FloorConstraint(name="range floor")] if floor else [])]
    return RangeJob(motion, int(start), int(end), tuple(chosen), int(blend), vae)
