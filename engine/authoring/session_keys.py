"""The keys of an authoring session and their bake (:class:`KeyEditing`, a base of
:class:`engine.authoring.session.AuthoringSession`).

Adding, moving and deleting keys and setting the animation's length, rate and in-between
rule are edits like any other (one undo step each, through the session's ``edit``); the
frame is part of a key's step, so its undo and redo show the frame the key is at.
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
from engine.authoring.history import Edit, History
from engine.authoring.jobs import BakeJob
from engine.authoring.keys import SCHEMES, Animation, Key
from engine.authoring.pose_mode import PoseMode
from engine.authoring.session_core import SessionCore
from engine.authoring.state import AuthoringState, holds_key, pose_between, pose_on_key, same_pose, same_target
from engine.errors import UserError
from engine.progress import CancelCheck, Progress

if TYPE_CHECKING:
    pass


class KeyEditing(SessionCore):
    """Keys, the animation and the bake of an authoring session (see the module doc);
    the session holds the state they read and write and the edit machinery, declared here."""

    mode: PoseMode
    scene: AuthoringScene
    baked: Baked | None
    events: ev.AuthoringEvents
    history: History
    _generation: int
    #: The frame last entered and the state it showed then: what an edit of an in-between
    #: is told from (:meth:`unkeyed_edit`).
    _shown: tuple[int, AuthoringState]

    if TYPE_CHECKING:

        @property
        def vae(self) -> Any: ...

        @property
        def animation(self) -> Animation: ...

        def _changed(self, before: AuthoringState, frame: int | None = None) -> None: ...

        def _put(self, state: AuthoringState) -> None: ...

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

        self.edit(f"key frame {frame}", change, framed=True)

    def delete_key(self, frame: int) -> None:
        """Delete the key at ``frame`` (nothing when there is none)."""
        if self.key_at(frame) is not None:
            self.edit(
                f"delete key {frame}",
                lambda: setattr(self.scene, "keys", [k for k in self.scene.keys if k.frame != frame]),
                framed=True,
            )

    def move_key(self, frame: int, to: int) -> None:
        """Move the key at ``frame`` to ``to`` (replacing a key there) and go there; undone,
        the frame it was made from is shown again (a view goes to the key first, so that is
        the key's)."""
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
            self._shown = (self.frame, self.state())

        self.edit(f"move key {frame} -> {to}", change, framed=True)

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
    @property
    def shown(self) -> tuple[int, AuthoringState]:
        """The frame last entered and the state it showed then (:meth:`unkeyed_edit`); a
        recovery sets it, so an edit not keyed before a crash is said after it too."""
        return self._shown

    @shown.setter
    def shown(self, value: tuple[int, AuthoringState]) -> None:
        self._shown = value

    def unkeyed_edit(self) -> bool:
        """Whether the pose on screen holds an edit that no key keeps, so going to another
        frame would drop it: on a key, a pose, targets, place or facing other than the
        key's; between keys, other than the in-between shown when the frame was entered.
        Without keys nothing is dropped (every frame keeps the pose)."""
        if not self.scene.keys or any(holds_key(self.mode, k) for k in self.scene.keys):
            return False
        if self.key_at(self.frame) is not None:
            return True
        frame, shown = self._shown
        if frame != self.frame:
            return False  # not entered by go_to (an autosave without it): nothing to tell it from
        targets = self.mode.targets
        same_targets = {t.joint for t in shown.targets} == set(targets) and all(
            same_target(t, targets[t.joint]) for t in shown.targets
        )
        return not (same_targets and same_pose(shown.pose, self.mode.pose) and shown.heading == self.mode.heading)

    def go_to(self, frame: int) -> int | None:
        """Make ``frame`` current: on a key the character takes the key's pose; between
        keys the baked in-between (its latent, place, facing and interpolated targets),
        so a key added there keeps the motion as it was. Bakes first when the bake is
        stale (on this thread: a view runs :meth:`bake_job` off its thread beforehand).

        Going to a frame is no undo step, unless it drops an :meth:`unkeyed_edit`: then
        it is one (Ctrl+Z goes back to the frame left, its edit as it was), and the frame
        left is returned (None otherwise). Going to the current frame keeps its edit."""
        frame = int(frame)
        dropped = self.unkeyed_edit()
        if dropped and frame == self.frame:
            return None
        before, old, shown = self.state(), self.frame, self._shown
        self.frame = frame
        self.pose_at(frame)
        after = self.state()
        self._shown = (frame, after)
        if dropped:
            # the frame is part of this step: undone, the edit is back on the frame it was made on
            text = f"drop unkeyed edit of frame {old}"
            self.history.push(Edit(text, (old, before, shown), (frame, after, self._shown), put=self._put_framed))
        self._changed(before, old)
        return old if dropped else None

    def _put_framed(self, framed: tuple[int, AuthoringState, tuple[int, AuthoringState]]) -> None:
        """Undo or redo of a step that changed the frame: the frame, the state and what
        the frame showed when entered, as they were."""
        frame, state, shown = framed
        before, old = self.state(), self.frame
        self._put(state)
        self.frame, self._shown = frame, shown
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
