"""The interface every reconstruction method implements (DragPoser, IK, autoencoder...).

A method is fed one :class:`SensorFrame` per frame and returns a :class:`FrameResult`.
It keeps whatever temporal state it needs between frames; :meth:`Method.reset`
starts a new clip.

What a method may offer beyond that is typed here, so callers check it with
``isinstance`` instead of probing attribute names: :class:`Configurable` (optimizer
settings by name), :class:`Constrainable` (the user's constraints),
:class:`SensorWeighted` (a weight per tracker), :class:`DecodesLatents` (a latent to a
pose) and :class:`SolvesClips` (a whole clip at once). The flags :attr:`Method.needs_ground_truth` and :attr:`Method.takes_deadline` say
how :mod:`engine.methods.driver` resets and steps it.
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from collections.abc import Iterable, Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any, Protocol, runtime_checkable

import numpy as np

from engine import skeleton as sk
from engine.errors import UserError
from engine.sensors import Sensor, SensorFrame

if TYPE_CHECKING:
    from engine.constraints.base import Constraint
    from engine.motion.clip import Motion


@dataclass
class FrameResult:
    """What a method produced for one frame.

    Attributes
    ----------
    local_rot : ndarray (22, 4)
        Local joint rotations; row 0 is the root's world rotation.
    root_pos : ndarray (3,)
        Root world position, metres.
    positions : ndarray (22, 3)
        World joint positions (FK of the above), metres.
    iterations : int
        Optimizer iterations spent on this frame (0 for non-iterative methods).
    losses : list of dict
        Per iteration, the value of every loss term by name plus ``"total"``.
    latent : ndarray (24,) or None
        Latent vector of the pose (latent-space methods only).
    ms : float
        Wall-clock time spent on the frame, milliseconds.
    warnings : list of str
        Problems met on this frame (e.g. a NaN target that was ignored).
    timings : dict of str to float
        Iterative methods: milliseconds per optimizer iteration on this frame,
        ``ms_per_iteration`` and its parts ``decoder``, ``fk_losses``, ``backward``,
        ``step`` (what ``bench`` reports and the studio's status bar can show).
    """

    local_rot: np.ndarray
    root_pos: np.ndarray
    positions: np.ndarray
    iterations: int = 0
    losses: list[dict[str, float]] = field(default_factory=list)
    latent: np.ndarray | None = None
    ms: float = 0.0
    warnings: list[str] = field(default_factory=list)
    timings: dict[str, float] = field(default_factory=dict)


class Method(ABC):
    """A reconstruction method: sensors in, full-body pose out, one frame at a time."""

    #: Short name used on the command line (``--method NAME``) and in the GUI.
    name: str = "method"

    #: True for methods that need the ground-truth clip (e.g. the autoencoder upper
    #: bound); callers then pass it to :meth:`reset` as ``reference``.
    needs_ground_truth: bool = False

    #: True for methods whose :meth:`step` takes ``deadline=`` (a ``time.perf_counter``
    #: time) and cuts its iterations short to end by then (live input).
    takes_deadline: bool = False

    @abstractmethod
    def reset(self, skeleton: sk.Skeleton, fps: float = sk.FPS, *, reference: Motion | None = None) -> None:
        """Start a new clip for a subject with the given skeleton.

        ``reference`` is the ground-truth clip; it is passed only to methods with
        :attr:`needs_ground_truth` set, so other methods may omit the keyword.
        """

    @abstractmethod
    def step(self, sensors: SensorFrame, deadline: float | None = None) -> FrameResult:
        """Reconstruct the next frame from its sensor readings.

        ``deadline`` (a ``time.perf_counter`` time) is given only to methods with
        :attr:`takes_deadline` set; the others may ignore it.
        """

    def between_frames(self) -> None:  # noqa: B027 - a no-op default that methods override
        """Work that can wait until the last frame's pose is out (a live loop calls it
        while waiting for the next frame; :meth:`step` does it first if nobody did).
        Results never depend on whether it was called. Nothing by default."""


@runtime_checkable
class Configurable(Protocol):
    """A method tuned by optimizer settings (:class:`engine.solver.OptimizerSettings` fields)."""

    def configure(self, **values: Any) -> None:
        """Change settings by name from the next frame; an unknown name raises
        :class:`~engine.errors.UserError` after the known ones are applied."""
        ...


@runtime_checkable
class Constrainable(Protocol):
    """A method that takes the user's constraints (:mod:`engine.constraints`)."""

    def set_constraints(self, constraints: Iterable[Constraint]) -> None:
        """Replace all user constraints (names unique); never mutates them."""
        ...

    def add_constraint(self, constraint: Constraint) -> None:
        """Add one constraint; a name in use raises :class:`~engine.errors.UserError`."""
        ...


@runtime_checkable
class SensorWeighted(Protocol):
    """A method that weights each tracker's term."""

    def set_sensor_weight(self, joint: str, weight: float) -> None:
        """Weight (>= 0, 1 = default) of the tracker on ``joint`` from the next frame."""
        ...


@runtime_checkable
class DecodesLatents(Protocol):
    """A latent-space method that can show the pose of any latent (the studio's debug view)."""

    def decode_latent(self, latent: np.ndarray) -> np.ndarray:
        """World joint positions ``(22, 3)``, metres, of ``latent (L,)`` at the current root."""
        ...


@runtime_checkable
class SolvesClips(Protocol):
    """A method that can solve a whole clip at once (DragPoser's batched offline mode)."""

    def solve_clip(self, frames: Sequence[SensorFrame]) -> list[FrameResult] | None:
        """One result per frame of the clip, right after :meth:`Method.reset`; None (the
        method left as reset) when this clip is to be solved frame by frame."""
        ...


def check_preset(readings: dict[str, Sensor], joints: tuple[str, ...], method: str, preset: str) -> None:
    """Raise a clear error unless the sensors are exactly ``joints``, all 6-DoF."""
    got = sorted(f"{j}:{r.dof}" for j, r in readings.items())
    want = sorted(f"{j}:6" for j in joints)
    if got != want:
        raise UserError(
            f"method {method!r} works only with sensor preset {preset!r} "
            f"({', '.join(joints)}, 6-DoF); got {', '.join(got) or 'no sensors'}"
        )
