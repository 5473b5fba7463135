"""The authoring model: a pose and its keys, edited through commands, announced by events.

:class:`AuthoringSession` owns the :class:`~engine.authoring.pose_mode.PoseMode` (the
character, its pose, the joint targets and the planted feet), the authored scene (keys,
animation, constraints), the current frame and the bake of the keys. It imports no Qt:
the pose window (:mod:`app.pose_window`) is a view that calls its methods and redraws on
its events (:mod:`engine.authoring.events`).

Every change is one command on :attr:`AuthoringSession.history` (Ctrl+Z undoes it
exactly: the command holds the state it touched before and after, see
:mod:`engine.authoring.state`), and fires one event per part it changed, with what
changed. A change that fails (a :class:`~engine.errors.UserError`) leaves the model as
it was and records nothing.

The pose's gestures (joints dragged and turned, the body moved, targets edited, the
settle) are the session's :class:`~engine.authoring.session_pose.PoseEditing` part; the
keys, the animation and the bake its
:class:`~engine.authoring.session_keys.KeyEditing` part. The bake (keys solved and
in-betweens, seconds for a long animation) is long work:
:meth:`AuthoringSession.bake_job` takes a copy of the scene for a worker thread, which
computes while the model stays untouched; :meth:`AuthoringSession.take_bake` then
applies the result on the model's own thread, unless an edit made it stale meanwhile.
"""

from __future__ import annotations

import dataclasses
import time
from collections.abc import Callable
from typing import Any

from engine.authoring import events as ev
from engine.authoring.bake import Baked
from engine.authoring.document import AuthoringScene
from engine.authoring.history import Edit, History
from engine.authoring.keys import Animation, Key
from engine.authoring.pose_mode import PoseMode
from engine.authoring.session_constraints import constraints_event
from engine.authoring.session_keys import KeyEditing
from engine.authoring.session_pose import PoseEditing
from engine.authoring.state import AuthoringState, capture, differences, holds_key, pose_on_key, put
from engine.editing.constraint_list import ConstraintList
from engine.errors import UserError
from engine.motion.clip import Motion


class AuthoringSession(PoseEditing, KeyEditing):
    """See the module doc.

    Parameters
    ----------
    mode : PoseMode
        The character and its starting pose.
    clock : callable, optional
        Seconds (monotonic) that decide which edits merge into one undo step.
    """

    def __init__(self, mode: PoseMode, clock: Callable[[], float] = time.monotonic) -> None:
        self.mode = mode
        self.scene = AuthoringScene(animation=Animation(), height=mode.character.height)
        self.scene.constraints = mode.constraints  # one list: the solves and the saved scene read it
        self.scene.pose_options = mode.options  # one object: the pose window's solves and the bake read it
        self.frame = 0
        self.baked: Baked | None = None
        self.events = ev.AuthoringEvents()
        self.history = History(self, self._history_changed)
        self._clock = clock
        self._generation = 0  # counts changes: a bake of an older scene is stale
        self.selected: str | None = None  # the joint whose rotation rings a view shows
        # the selection before the press that selected the joint held: a drag's step gives it back
        self._before_press: tuple[str | None] | None = None
        self._shown = (self.frame, self.state())

    @property
    def frame(self) -> int:
        """The animation frame shown and posed (the pose's solves weigh each constraint by
        its activity on this frame, as the bake does)."""
        return self._frame

    @frame.setter
    def frame(self, value: int) -> None:
        self._frame = int(value)
        self.mode.frame = self._frame

    @classmethod
    def new(
        cls, height: float | None = None, motion: Motion | None = None, frame: int = 0, vae: Any = None
    ) -> AuthoringSession:
        """A session on a character ``height`` metres tall (None: the canonical one),
        standing in the VAE's mean pose, or in frame ``frame`` of ``motion`` when given;
        ``vae`` None loads the shipped pose VAE."""
        if vae is None:
            from engine.models import load_default_models

            vae = load_default_models().vae
        mode = PoseMode(vae, height) if motion is None else PoseMode.from_clip_frame(vae, motion, frame, height)
        return cls(mode)

    @property
    def vae(self) -> Any:
        return self.mode.character.vae

    @property
    def animation(self) -> Animation:
        return self.scene.animation

    @property
    def keys(self) -> list[Key]:
        return self.scene.keys

    targets = property(lambda self: self.mode.targets, doc="The pose mode's targets by joint.")
    pose = property(lambda self: self.mode.pose, doc="The pose on screen (:class:`Pose`).")

    @property
    def dirty(self) -> bool:
        """Whether there are edits since the scene was opened or saved."""
        return not self.history.is_clean()

    # -- state, commands and events ------------------------------------------------
    def state(self) -> AuthoringState:
        """The model now, as immutable copies (what a command records)."""
        return capture(self.mode, self.scene, self.selected)

    def _put(self, state: AuthoringState) -> None:
        put(self.mode, self.scene, state)
        self.selected = state.selected

    def select(self, joint: str | None, pressed: bool = False) -> None:
        """Select ``joint`` (None: none). No undo step of its own: every step records the
        selection, so undo and redo give it back. ``pressed``: a mouse press selected it,
        and the drag it may start is edited next; that drag's step records the selection
        before the press, so undoing the drag leaves the rings where they were before it
        (:meth:`release` when the button is up)."""
        if pressed:
            self._before_press = (self.selected,)
        elif joint != self.selected:
            self._before_press = None
        self.selected = joint

    def release(self) -> None:
        """The mouse button of the last :meth:`select` press is up: edits from now on are
        not its drag."""
        self._before_press = None

    def restore_state(self, state: AuthoringState) -> None:
        """Make ``state`` the model's and announce what that changed (undo and redo)."""
        before = self.state()
        self._put(state)
        self._changed(before)

    def edit(
        self,
        text: str,
        change: Callable[[], Any],
        key: tuple | None = None,
        solve: bool = False,
        framed: bool = False,
    ) -> None:
        """Run ``change()`` (then a solve of the pose, with ``solve``) as one undo step
        named ``text``; ``key`` (see :class:`engine.authoring.history.Edit`) merges a drag's
        moves into one step. ``framed``: the frame is part of the step, so its undo and
        redo show the frame they leave the model on (an edit of the keys: the key's frame).
        On a UserError the model is put back and it is raised."""
        before, frame, began, shown = self.state(), self.frame, self._clock(), self._shown
        try:
            change()
            if solve:
                self.mode.solve()
        except UserError:
            self._put(before)
            self.frame, self._shown = frame, shown
            raise
        recorded = before
        if self._before_press is not None:
            recorded = dataclasses.replace(before, selected=self._before_press[0])
            self._before_press = None
        if framed:
            edit = Edit(
                text,
                (frame, recorded, shown),
                (self.frame, self.state(), self._shown),
                key,
                self._clock(),
                put=self._put_framed,
                began=began,
            )
        else:
            edit = Edit(text, recorded, self.state(), key, self._clock(), began=began)
        self.history.push(edit)
        self._changed(before, frame)

    def _changed(self, before: AuthoringState, frame: int | None = None) -> None:
        """Announce every part that differs from ``before``; a changed scene makes the bake stale."""
        after = self.state()
        d = differences(before, after)
        if d.keys or d.animation or d.constraints:
            self._generation += 1
            self._stale()
        if frame is not None and frame != self.frame:
            self.events.frame.emit(ev.FrameChanged(self.frame, frame))
        if d.joints:
            self.events.targets.emit(ev.TargetsChanged(after.targets, d.joints))
        if d.constraints:
            self.events.constraints.emit(constraints_event(before.constraints, after.constraints))
        if d.keys:
            self.events.keys.emit(
                ev.KeysChanged(tuple(k.frame for k in after.keys), d.keys_added, d.keys_removed, d.keys_changed)
            )
        if d.animation:
            frames, fps, interpolation = after.animation
            self.events.animation.emit(ev.AnimationChanged(frames, fps, interpolation, before.animation))
        if d.pose:
            self.events.pose.emit(ev.PoseChanged(after.pose, after.heading, before.heading))
        if d.selection:
            self.events.selection.emit(ev.SelectionChanged(after.selected, before.selected))

    def _stale(self) -> None:
        if self.baked is not None:
            self.baked = None
            self.events.bake.emit(ev.BakeChanged(None))

    def _history_changed(self) -> None:
        h = self.history
        self.events.history.emit(
            ev.HistoryChanged(h.can_undo(), h.can_redo(), h.undo_text(), h.redo_text(), h.is_clean(), h.count())
        )

    def undo(self) -> None:
        self.history.undo()

    def redo(self) -> None:
        self.history.redo()

    # -- constraints ---------------------------------------------------------------
    constraint_catalog = staticmethod(ConstraintList.catalog)  # the kinds users may add, with their fields

    def add_constraint(self, kind: str, **params: Any) -> None:
        """Add a ``kind`` constraint with ``params`` and solve (:meth:`_constraint_edit`)."""
        self._constraint_edit(f"add {kind}", lambda: ConstraintList(self.mode.constraints).add(kind, **params))

    def remove_constraint(self, name: str) -> None:
        self._constraint_edit(f"remove {name}", lambda: ConstraintList(self.mode.constraints).remove(name))

    def update_constraint(self, name: str, changes: dict[str, Any]) -> None:
        """Set fields of the constraint ``name`` and solve (a slider's steps merge)."""
        self._constraint_edit(
            f"edit {name}",
            lambda: ConstraintList(self.mode.constraints).edit(name, **changes),
            ("constraint", name, tuple(changes)),
        )

    def _constraint_edit(self, text: str, change: Callable[[], Any], key: tuple | None = None) -> None:
        """Run the constraint list's ``change()`` as the undo step ``text`` (``key`` merges
        a slider's steps) and pose the character under the new list.

        A constraint is part of the scene, not of a key's pose: on a key that the pose
        holds (:func:`~engine.authoring.state.holds_key`: no unkeyed edit on it) the
        key is posed again as the bake poses it on its frame
        (:func:`~engine.authoring.state.pose_on_key`: its latent, where it stands, its
        targets, the pins acting there winning over them), so the key stays what it
        was and the frame shows what the bake gives there. Elsewhere (an in-between, a
        key with an edit not keyed, no keys) the pose is solved again with the list."""
        shown = self.key_at(self.frame)
        if shown is None or shown.latent is None or not holds_key(self.mode, shown):
            self.edit(text, change, key, solve=True)
            return

        def posed() -> None:
            change()
            pose_on_key(self.mode, shown)

        self.edit(text, posed, key)

    # -- documents -----------------------------------------------------------------
    def new_scene(self, height: float | None = None) -> None:
        """Make a new, empty document (File ▸ New pose): a character ``height`` metres tall
        (None: the canonical one) in the pose model's mean pose, whatever pose the window
        started from, with no keys, targets, constraints or selection, the default
        animation and settings, and a new undo history."""
        self.open_scene(AuthoringScene(height=height), fresh=True)

    def open_scene(self, loaded: AuthoringScene, fresh: bool = False) -> None:
        """Make ``loaded`` the document: its keys, animation, constraints and settings (and
        its character's height), at its first key, with a new undo history. ``fresh``: the
        character starts from the pose model's mean pose and nothing is selected (a new
        document, :meth:`new_scene`); else it keeps the pose it was started from."""
        from engine.skeleton import Skeleton

        before, old = self.state(), self.frame
        height = loaded.height if loaded.height is not None else Skeleton.canonical().height()
        if fresh or abs(height - self.mode.character.height) > 1e-6:
            shared = self.mode.constraints
            self.mode = PoseMode(self.vae, height, options=self.mode.options)
            self.mode.constraints = shared
        if fresh:
            self.selected = None
        m = self.mode
        m.options = self.scene.pose_options = loaded.pose_options
        m.constraints[:] = list(loaded.constraints)
        self.scene.keys, self.scene.animation, self.scene.settings = loaded.keys, loaded.animation, loaded.settings
        self.scene.height = m.character.height
        m.targets, m.heading = {}, 0.0
        m.pose = m.character.decode(m.base_latent, m.character.grounded())  # where a scene without keys starts
        m.plant_where_standing()
        self._stale()
        self.frame = loaded.keys[0].frame if loaded.keys else 0
        self.pose_at(self.frame)
        self._shown = (self.frame, self.state())
        self._changed(before, old)
        self.history.clear()
