"""What the session loads: clips (any supported BVH rig) and named sensor sets."""

from __future__ import annotations

from pathlib import Path

from engine.errors import UserError
from engine.motion.clip import Motion
from engine.motion.retarget import load_with_report, resample_motion
from engine.sensors import Sensor
from engine.tracking import PRESET_SENSORS


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
