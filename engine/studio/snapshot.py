"""What the engine thread publishes: one solved frame as plain, read-only numpy data.

Widgets are typed against :class:`Snapshot`; it holds numbers, strings and read-only
arrays only, never an engine object.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from engine.gizmos import Gizmo
from engine.studio.latent_views import LatentDetail, LatentView


def readonly(a: Any) -> Any:
    """A read-only copy of an array (other values pass through)."""
    if isinstance(a, np.ndarray):
        a = a.copy()
        a.flags.writeable = False
    return a


HISTORY = 600  # solved frames a snapshot carries in ``history``


@dataclass(frozen=True)
class HistoryEntry:
    """What the plots keep of one solved frame.

    Attributes
    ----------
    frame : int
        Frame index.
    iterations : int
        Optimizer iterations spent; ``ms`` the solve's wall time in milliseconds.
    losses : dict of str to float
        Every loss term's value after the last iteration (plus ``"total"``).
    latent : ndarray (L,) or None
        The frame's latent vector, for methods that have one.
    readouts : dict of str to float
        The frame's place on the latent map and prior readouts (``x, y, nearest, norm,
        predictor, flagged``; :meth:`LatentView.readouts`), empty without a latent.
    """

    frame: int
    iterations: int
    ms: float
    losses: dict[str, float]
    latent: np.ndarray | None = None
    readouts: dict[str, float] = field(default_factory=dict)


@dataclass(frozen=True)
class Snapshot:
    """One solved frame, as plain read-only numpy data.

    Attributes
    ----------
    seq : int
        Increases with every snapshot (cheap change detection for readers).
    frame, num_frames : int
        Frame index shown and clip length.
    positions : ndarray (22, 3)
        World joint positions of the reconstruction, metres.
    ground_truth : ndarray (22, 3)
        World joint positions of the loaded clip at ``frame``.
    ghosts : dict of str to ndarray (22, 3)
        Other methods' reconstructions of the same frame.
    target_joints : tuple of str
        Sensors sent to the method, in order; ``target_positions`` (S, 3),
        ``target_rotations`` (S, 4) and ``target_connected`` (S,) bool follow it.
    gizmos : tuple of (str, Gizmo)
        The enabled constraints that draw a shape (:mod:`engine.gizmos`), by name.
    losses : tuple of dict
        Per optimizer iteration, every loss term by name plus ``"total"``.
    latent : ndarray (L,) or None
        The method's latent vector for this frame.
    iterations : int
        Optimizer iterations spent on the frame; ``ms`` wall time of the solve.
    warnings : int
        Warnings counted since the clip was loaded; ``messages`` holds this frame's.
    error : str
        Non-empty when the method failed on this frame (the pose is the last good one).
    method_error : str
        Non-empty (once) when a requested method could not be built; the engine kept the
        method it had, which ``method`` names.
    engine_fps : float
        Solved frames per second (moving average).
    configurable : bool
        Whether the shown method takes optimizer settings (the studio says so when it
        takes none).
    decoded : ndarray (22, 3) or None
        Pose decoded from a latent sent with :class:`DecodeLatent` (debug mode).
    solved : int
        Frames solved since the engine started (counts every solve, for rates).
    frames_skipped : int
        Clip frames playback passed over without solving them, since playback started
        (always 0 at the ``"every_frame"`` pace); ``pace`` is the playback pace.
    timing : dict of str to float
        The method's own timing of the frame's solve, milliseconds by name (e.g.
        ``ms_per_iteration``), when it reports one.
    recent_errors : tuple of str
        The last few problems reported since the clip was loaded, oldest first (``error``
        holds only the one that arrived with this frame).
    plays : int
        Play commands the engine has received; a reader tells a snapshot that reports
        the end of playback from one that predates its latest play request.
    history : tuple of HistoryEntry
        The last :data:`HISTORY` solved frames, oldest first, including frames whose
        snapshots a reader skipped (the GUI draws only the newest one); cleared when
        playback jumps (seek back, loop, new clip or method).
    history_run : int
        How many times ``history`` has been cleared. A reader that keeps its own series
        per frame starts it again when this changes: it may never have drawn the frame
        before a jump, so the frames it saw cannot tell it that one happened.
    opened : int
        The ``opened`` number of the newest clip, source or method the engine took
        (:class:`engine.studio.commands.SetMotion`): a snapshot whose number is below the
        session's ``opened`` shows what was open before.
    latent_view : LatentView or None
        The solved frame on the latent map, with its readouts (latent-space methods).
    latent_detail : LatentDetail or None
        The frame's term forces and dimension sweep, after an ``InspectLatent`` request.
    latent_note : str
        Why there is no ``latent_view`` (e.g. the method has no latent), "" otherwise.
    """

    seq: int
    frame: int
    num_frames: int
    positions: np.ndarray
    ground_truth: np.ndarray
    ghosts: dict[str, np.ndarray] = field(default_factory=dict)
    target_joints: tuple[str, ...] = ()
    target_positions: np.ndarray = field(default_factory=lambda: np.zeros((0, 3)))
    target_rotations: np.ndarray = field(default_factory=lambda: np.zeros((0, 4)))
    target_connected: np.ndarray = field(default_factory=lambda: np.zeros(0, bool))
    gizmos: tuple[tuple[str, Gizmo], ...] = ()
    losses: tuple[dict[str, float], ...] = ()
    latent: np.ndarray | None = None
    iterations: int = 0
    ms: float = 0.0
    warnings: int = 0
    messages: tuple[str, ...] = ()
    error: str = ""
    method_error: str = ""
    engine_fps: float = 0.0
    playing: bool = False
    method: str = ""
    can_decode: bool = False
    configurable: bool = True
    decoded: np.ndarray | None = None
    history: tuple[HistoryEntry, ...] = ()
    history_run: int = 0
    opened: int = 0
    solved: int = 0
    frames_skipped: int = 0
    pace: str = "every_frame"
    timing: dict[str, float] = field(default_factory=dict)
    recent_errors: tuple[str, ...] = ()
    plays: int = 0
    latent_view: LatentView | None = None
    latent_detail: LatentDetail | None = None
    latent_note: str = ""
