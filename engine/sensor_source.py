"""Where the engine's per-frame sensor readings come from: the one contract every source
implements, and the one way the studio's sensor edits are applied to readings.

A :class:`SensorSource` gives, per frame, the readings of the session's sensors with the
studio's edits applied (:func:`apply_edits`: disabled sensors dropped, 3-DoF sensors
without rotation, simulated failures disconnected, drag offsets added), plus the
reference pose drawn as "ground truth" when there is one. The sources are a clip's
simulated trackers (:class:`engine.studio.clip_source.ClipSource`), a tracker recording
(:class:`engine.tracker_io.recording_source.RecordingSource`) and a live stream
(:class:`engine.tracker_io.live_source.LiveSource`); the studio installs one with
:class:`engine.studio.commands.SetSource`.
"""

from __future__ import annotations

from abc import abstractmethod
from collections.abc import Mapping
from typing import TYPE_CHECKING, Protocol

import numpy as np

from engine import skeleton as sk
from engine.sensors import Sensor, SensorFrame

if TYPE_CHECKING:
    from engine.motion.clip import Motion

_IDENTITY = np.array([1.0, 0.0, 0.0, 0.0])


class SensorSource(Protocol):
    """Per-frame sensor readings for the engine (see the module doc).

    Subclass it: the abstract members are required, the others have the defaults of a
    source with no ground truth that ends on its own (no network, nothing to close).

    Attributes
    ----------
    sensors : tuple of Sensor
        The session's sensors, settings only (set through :meth:`set_sensors`).
    motion : Motion or None
        The clip behind the source, when there is one (the ground truth a method may need).
    skeleton : Skeleton
        The subject's skeleton, which methods are reset with (a clip's own, or a
        wearer's calibrated one).
    skeleton_version : int
        Bumped whenever :attr:`skeleton` changes while the source runs (the engine then
        resets its methods).
    live : bool
        Frames arrive on a network's schedule: playback follows the newest one instead
        of a clock.
    """

    sensors: tuple[Sensor, ...] = ()
    motion: Motion | None = None
    skeleton: sk.Skeleton
    skeleton_version: int = 0
    live: bool = False

    @property
    @abstractmethod
    def fps(self) -> float:
        """Frames per second of the stream."""

    @property
    @abstractmethod
    def num_frames(self) -> int:
        """Frames available (0 while there are none)."""

    @abstractmethod
    def frame(self, frame: int) -> SensorFrame:
        """Readings of the enabled sensors at ``frame`` with the studio's edits applied."""

    def ground_truth(self, frame: int) -> np.ndarray:
        """Reference world joint positions (22, 3), metres; NaN when there is none."""
        return np.full((sk.NUM_JOINTS, 3), np.nan)

    def set_sensors(self, sensors: tuple[Sensor, ...]) -> None:
        """The session's sensors changed (their settings: enabled, DoF, offset...)."""
        self.sensors = tuple(sensors)

    def arrival(self, frame: int) -> float | None:
        """``time.perf_counter()`` when ``frame`` arrived (latency), None when unknown."""
        return None

    def close(self) -> None:
        """Release what the source holds (a socket, a recording in progress)."""
        return None  # a default, not an abstract member (an empty Protocol body would be)


def apply_edits(readings: Mapping[str, Sensor], sensors: tuple[Sensor, ...], frame: int) -> SensorFrame:
    """``readings`` (raw samples by joint) as the studio's ``sensors`` have them.

    Only enabled sensors with a reading are kept, each with its drag offset added, an
    identity rotation when it is 3-DoF (no ground truth leaks through) and disconnected
    inside its simulated failures; the sensor's settings travel with the sample. With no
    sensors set, the readings pass unchanged (a stream before the studio names any).
    """
    if not sensors:
        return SensorFrame(frame, dict(readings))
    out: dict[str, Sensor] = {}
    for s in sensors:
        r = readings.get(s.joint)
        if r is None or not s.enabled:
            continue
        position = np.asarray(r.position, float) + np.asarray(s.offset, float)
        rotation = np.asarray(r.rotation, float) if s.dof == 6 else _IDENTITY.copy()
        out[s.joint] = s.read(position, rotation, bool(r.connected) and not s.lost_at(frame))
    return SensorFrame(frame, out)
