"""What the session loads: clips (any supported BVH rig) and named sensor sets; where a
tracker is on a frame of them."""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from engine import skeleton as sk
from engine.errors import UserError
from engine.motion.clip import Motion
from engine.motion.retarget import load_with_report, resample_motion
from engine.sensors import Sensor
from engine.tracking import PRESET_SENSORS

if TYPE_CHECKING:
    from engine.sensor_source import SensorSource
    from engine.studio.snapshot import Snapshot


def sensor_presets() -> dict[str, tuple[Sensor, ...]]:
    """Preset name -> its sensors (``assets/presets/sensors.json``), in preset order."""
    return dict(PRESET_SENSORS)


def load_clip(path: str | Path, rig_map: str | Path | None = None, own_rate: bool = False) -> Motion:
    """Load any supported BVH onto the canonical skeleton (60 fps, floor at z = 0);
    ``rig_map`` is a joint mapping file (``--rig-map``) used instead of rig detection;
    ``own_rate``: resampled back to the file's own frame rate (a video of it plays as
    many frames per second as the file has).

    Raises
    ------
    UserError
        When the file is missing, malformed or of an unknown rig; the message names it.
    """
    path = Path(path)
    if not path.is_file():
        raise UserError(f"{path}: no such file")
    try:
        motion, report = load_with_report(path, rig_map=rig_map)
        if own_rate and abs(report.source_fps - motion.fps) > 1e-6:
            motion = resample_motion(motion, report.source_fps)
        return motion
    except UserError:
        raise
    except Exception as exc:  # a malformed file must never take the studio down
        raise UserError(f"{path}: cannot read ({type(exc).__name__}: {exc})") from exc


def tracked_position(
    joint: str,
    frame: int,
    snap: Snapshot | None,
    source: SensorSource | None,
    motion: Motion | None,
    sensor: Sensor | None,
) -> np.ndarray:
    """Where ``joint``'s tracker is at ``frame`` before any drag offset, (3,) metres.

    Read from ``snap`` (the engine's newest snapshot) when it shows ``frame``, with no
    kinematics on the caller's thread; with a tracker ``source`` (no ground truth), its
    reading less ``sensor``'s offset; otherwise from the forward kinematics of the
    clip's frame; zeros when there is nothing to read.
    """
    j = sk.JOINT_INDEX[joint]
    if snap is not None and snap.frame == frame and np.all(np.isfinite(snap.ground_truth[j])):
        return np.array(snap.ground_truth[j])
    if source is not None:
        r = source.frame(frame).readings.get(joint)
        if r is None:
            return np.zeros(3)
        return np.asarray(r.position, float) - np.asarray(sensor.offset if sensor is not None else 0.0)
    if motion is None:
        return np.zeros(3)
    frame = int(np.clip(frame, 0, len(motion) - 1))
    return motion.slice(frame, frame + 1).positions()[0, j]
