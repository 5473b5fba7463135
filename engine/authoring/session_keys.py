"""The keys of an authoring session and their bake (:class:`KeyEditing`, a base of
:class:`engine.authoring.session.AuthoringSession`).

Adding, moving and deleting keys and setting the animation's length, rate and in-between
rule are edits like any other (one undo step each, through the session's ``edit``).
Going to a frame poses the character on it: a key's pose, or between keys the baked
in-between. The bake is long work: :meth:`KeyEditing.bake_job` copies the scene for a
worker thread and :meth:`KeyEditing.take_bake` takes the result unless an edit made it
stale meanwhile.
"""

from __future__ import annotations

import copy
from typing import TYPE_CHECKING, Any

from engine.authoring import events as ev
from engine.authoring.bake import Baked
from engine.authoring.document import MAX_FRAMES, AuthoringScene
from engine.authoring.jobs import BakeJob
from engine.authoring.keys import SCHEMES, Animation, Key
from engine.authoring.pose_mode import PoseMode
from engine.authoring.state import AuthoringState, pose_between, pose_on_key
from engine.errors import UserError
from engine.progress import CancelCheck, Progress

if TYPE_CHECKING:
    from collections.abc import Callable


class KeyEditing:
    """Keys, the animation and the bake of an authoring session (see the module doc);
    the session holds the state they read and write and the edit machinery, declared here."""

    mode: PoseMode
    scene: AuthoringScene
    baked: Baked | None
    events: ev.AuthoringEvents
    _generation: int

    if TYPE_CHECKING:
        frame: int

        @property
        def vae(self) -> Any: ...

        @property
        def animation(self) -> Animation: ...

        def state(self) -> AuthoringState: ...

        def edit(self, text: str, change: Callable[[], Any], key: tuple | None = None, solve: bool = False) -> None: ...

        def _changed(self, before: AuthoringState, frame: int | None = None) -> None: ...

    # -- keys and the animation ----------------------------------------------------
    def key_at(self, frame: int) -> Key | None:
        return next((k for k in self.scene.keys if k.frame == frame), None)

    def add_key(self, frame: int) -> None:
        """The current pose (latent, targets, where it stands, facing) as the key at ``frame``."""
        p, m = self.mode.pose, self.mode

        def change() -> None:
            key = Key(int(frame), copy.deepcopy(m.targets), p.latent.copy(), m.standing_place(), m.heading)
            if m.pelvis_target() is not None:  # the legs reach where the feet were planted
                key.feet = {j: f.copy() for j, f in m.planted.items()}
            self.scene.keys = sorted([*(k for k in self.scene.keys if k.frame != frame), key], key=lambda k: k.frame)

        self.edit(f"key frame {frame}", change)

    def delete_key(self, frame: int) -> None:
        """Delete the key at ``frame`` (nothing when there is none)."""
        if self.key_at(frame) is not None:
            self.edit(
                f"delete key {frame}",
                lambda: setattr(self.scene, "keys", [k for k in self.scene.keys if k.frame != frame]),
            )

    def move_key(self, frame: int, to: int) -> None:
        """Move the key at ``frame`` to ``to`` (replacing a key there) and go there."""
        key = self.key_at(frame)
        if key is None or frame == to or not 0 <= to < self.scene.animation.frames:
            return

        def change() -> None:
            moved = copy.deepcopy(key)
            moved.frame = int(to)
            kept = [k for k in self.scene.keys if k.frame not in (frame, to)]
            self.scene.keys = sorted([*kept, moved], key=lambda k: k.frame)
            self.frame = int(to)
            self.pose_at(self.frame)  # inside the step: undo and redo give back the pose shown

        self.edit(f"move key {frame} -> {to}", change)

    def set_length(self, frames: int) -> None:
        """The animation's length, frames."""
        if not 1 <= int(frames) <= MAX_FRAMES:
            raise UserError(f"length must be 1-{MAX_FRAMES} frames, got {frames}")
        self.edit("length", lambda: setattr(self.scene.animation, "frames", int(frames)))

    def set_fps(self, fps: float) -> None:
        """The animation's rate, frames per second."""
        if not 1.0 <= float(fps) <= 240.0:
            raise UserError(f"rate must be 1-240 frames per second, got {fps}")
        self.edit("rate", lambda: setattr(self.scene.animation, "fps", float(fps)))

    def set_interpolation(self, scheme: str) -> None:
        """How in-betweens are made: one of :data:`engine.authoring.keys.SCHEMES`."""
        if scheme not in SCHEMES:
            raise UserError(f"in-betweens: {scheme!r} is not one of {', '.join(SCHEMES)}")
        self.edit("in-betweens", lambda: setattr(self.scene.animation, "interpolation", scheme))

    # -- frames and the bake -------------------------------------------------------
    def go_to(self, frame: int) -> None:
        """Make ``frame`` current: on a key the character takes the key's pose; between
        keys the baked in-between (its latent, place, facing and interpolated targets),
        so a key added there keeps the motion as it was. Not an undo step. Bakes first
        when the bake is stale (on this thread: a view runs :meth:`bake_job` off its
        thread beforehand)."""
        before, old = self.state(), self.frame
        self.frame = int(frame)
        self.pose_at(self.frame)
        self._changed(before, old)

    def pose_at(self, frame: int) -> None:
        """Pose the character as ``frame`` shows it: on a key the key's pose, between keys
        the baked in-between; nothing without keys."""
        key = self.key_at(frame)
        if key is not None:
            pose_on_key(self.mode, key)
        elif self.scene.keys:
            pose_between(self.mode, self.bake_now(), self.scene.keys, self.animation.interpolation, frame)

    def bake_job(self) -> BakeJob:
        """The bake of the keys as it stands, to run on any thread (:meth:`take_bake`)."""
        if not self.scene.keys:
            raise UserError("add at least one key first")
        scene = AuthoringScene(
            list(self.scene.constraints),
            self.scene.settings,
            copy.copy(self.scene.animation),
            [copy.deepcopy(k) for k in self.scene.keys],
            self.scene.height,
            pose_options=copy.copy(self.scene.pose_options),
        )
        return BakeJob(scene, self.vae, self._generation)

    def take_bake(self, job: BakeJob, baked: Baked) -> bool:
        """Make ``baked`` (``job``'s result) the bake, unless the scene changed since the
        job was made; whether it was taken."""
        if job.generation != self._generation:
            return False
        self.baked = baked
        self.events.bake.emit(ev.BakeChanged(baked))
        return True

    def bake_now(self, progress: Progress | None = None, cancelled: CancelCheck | None = None) -> Baked:
        """The bake, baked on this thread when it is stale (raises Cancelled when ``cancelled()``)."""
        if self.baked is None:
            job = self.bake_job()
            self.take_bake(job, job.run(progress, cancelled))
        assert self.baked is not None
        return self.baked
