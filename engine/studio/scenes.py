"""The session's scene files: one format with :mod:`engine.scene`, plus the studio's keys.

A studio scene is an optimizer scene (``format``, ``version``, ``settings``,
``constraints``: read and checked by :func:`engine.scene.scene_from_dict`, so the CLI's
``--scene`` reads it too) with the studio's own keys: ``clip`` (path), ``method``,
``preset``, ``sensors`` and ``frame``.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping
from pathlib import Path
from typing import Any

from engine import scene as optimizer_scene
from engine.constraints.base import Constraint
from engine.errors import UserError
from engine.sensors import Sensor
from engine.solver import OptimizerSettings
from engine.solver.settings import SettingsEdit


#: Settings a session sets from the start (at the optimizer's defaults); the others stay
#: unset, so a method's sensor-set profile supplies them (``engine/solver/profiles.py``).
SESSION_SETTINGS = ("mode", "iterations", "lr", "temporal_weight")


def default_settings() -> SettingsEdit:
    """The optimizer's own defaults of :data:`SESSION_SETTINGS`."""
    d = OptimizerSettings()
    return SettingsEdit({name: getattr(d, name) for name in SESSION_SETTINGS})



def scene_to_dict(path: Path | None, method: str, preset: str, sensors: Iterable[Sensor],
                  constraints: Iterable[Constraint], settings: Mapping[str, Any], frame: int) -> dict[str, Any]:  # fmt: skip
    """Plain-JSON description of a session's scene (the clip by path)."""
    doc = optimizer_scene.scene_to_dict(constraints, dict(settings))
    doc.update({
        "clip": str(path) if path else None,
        "method": method,
        "preset": preset,
        "sensors": [s.to_dict() for s in sensors],
        "frame": int(frame),
    })  # fmt: skip
    return doc


def scene_from_dict(scene: Any, where: str = "scene") -> dict[str, Any]:
    """Check and convert :func:`scene_to_dict` output; errors name ``where`` and the entry.

    Returns a dict with ``method`` (str), ``preset`` (str), ``sensors`` (tuple of
    Sensor), ``constraints`` (list of Constraint), ``settings`` (a :class:`SettingsEdit`
    of the settings the scene gives), ``frame`` (int).
    """
    constraints, settings = optimizer_scene.scene_from_dict(scene, where)  # also checks it is an object
    sensors = scene.get("sensors", [])
    if not isinstance(sensors, list):
        raise UserError(f"{where}: field 'sensors' must be a list")
    sensors = tuple(Sensor.from_dict(s, f"{where}: sensors[{i}]") for i, s in enumerate(sensors))
    given = scene.get("settings") or {}
    try:
        frame = int(scene.get("frame", 0))
    except (TypeError, ValueError):
        raise UserError(f"{where}: field 'frame' must be an integer") from None
    return {"method": str(scene.get("method") or ""), "preset": str(scene.get("preset") or ""),
            "sensors": sensors, "constraints": constraints,
            "settings": SettingsEdit({k: getattr(settings, k) for k in given}, where), "frame": frame}  # fmt: skip
