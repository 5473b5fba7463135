"""Typed events of the authoring model (psygnal signals, as the studio's
:mod:`engine.studio.events`; the constraint list's payload is
:class:`engine.editing.events.ConstraintsChanged`, shared with the studio).

Each signal of :class:`AuthoringEvents` carries one frozen payload that says what
changed, so a view redraws only that part::

    session.events.targets.connect(lambda ev: print(ev.joints))

Every event fires on the thread that called the session method (the GUI thread: long
work runs on a worker and the GUI thread applies its result).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

from psygnal import Signal, SignalGroup

from engine.editing.events import ConstraintsChanged

if TYPE_CHECKING:
    from engine.authoring.bake import Baked
    from engine.authoring.character import Pose
    from engine.authoring.targets import JointTarget

__all__ = [
    "AnimationChanged",
    "AuthoringEvents",
    "BakeChanged",
    "ConstraintsChanged",
    "FrameChanged",
    "HistoryChanged",
    "KeysChanged",
    "PoseChanged",
    "SelectionChanged",
    "TargetsChanged",
]


@dataclass(frozen=True)
class TargetsChanged:
    """The joint targets changed: ``joints`` names those added, removed or edited;
    ``targets`` is the whole set after the change."""

    targets: tuple[JointTarget, ...]
    joints: tuple[str, ...]


@dataclass(frozen=True)
class PoseChanged:
    """The character's pose (and maybe its facing, degrees about +Z) changed."""

    pose: Pose
    heading: float
    old_heading: float


@dataclass(frozen=True)
class KeysChanged:
    """Keys were added, removed or changed (their frames, before and after)."""

    frames: tuple[int, ...]
    added: tuple[int, ...] = ()
    removed: tuple[int, ...] = ()
    changed: tuple[int, ...] = ()


@dataclass(frozen=True)
class AnimationChanged:
    """Length (frames), rate (frames per second) or in-between scheme changed;
    ``old`` is the previous ``(frames, fps, interpolation)``."""

    frames: int
    fps: float
    interpolation: str
    old: tuple[int, float, str]


@dataclass(frozen=True)
class FrameChanged:
    """The current frame changed."""

    frame: int
    old: int


@dataclass(frozen=True)
class HistoryChanged:
    """The undo history changed: what Undo and Redo would do, whether the scene is as
    last saved (``clean``) and how many steps there are."""

    can_undo: bool
    can_redo: bool
    undo_text: str
    redo_text: str
    clean: bool
    count: int


@dataclass(frozen=True)
class SelectionChanged:
    """Undo or redo gave back another selected joint (None: none)."""

    selected: str | None
    old: str | None


@dataclass(frozen=True)
class BakeChanged:
    """The bake of the keys: a new one, or None when an edit made it stale."""

    baked: Baked | None


class AuthoringEvents(SignalGroup):
    """The authoring model's signals; connect with ``session.events.NAME.connect(callback)``."""

    targets = Signal(TargetsChanged)
    pose = Signal(PoseChanged)
    keys = Signal(KeysChanged)
    animation = Signal(AnimationChanged)
    constraints = Signal(ConstraintsChanged)
    frame = Signal(FrameChanged)
    history = Signal(HistoryChanged)
    bake = Signal(BakeChanged)
    selection = Signal(SelectionChanged)
