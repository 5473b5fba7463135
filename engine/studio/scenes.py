"""The session's scene files: one format with :mod:`engine.scene`, plus the studio's keys.

A studio scene is an optimizer scene (``format``, ``version``, ``settings``,
``constraints``: read and checked by :func:`engine.scene.scene_from_dict`, so the CLI's
``--scene`` reads it too) with the studio's own keys: ``clip`` (path), ``method``,
``preset``, ``sensors`` and ``frame``. A scene of the pose window (``character``,
``animation``, ``keys``) is checked exactly as ``bake`` checks it
(:func:`engine.authoring.document.authoring_from_dict`), so a file the studio loads
also bakes. What a scene leaves out (sensors, preset, method, frame) the studio keeps;
:func:`describe_load` says what a load replaced and what it kept.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping
from pathlib import Path
from typing import Any

from engine import scene as optimizer_scene
from engine.authoring.document import authoring_from_dict
from engine.constraints.base import Constraint
from engine.errors import UserError
from engine.sensors import Sensor
from engine.solver import OptimizerSettings
from engine.solver.settings_edit import SettingsEdit
from engine.validation import shown

#: Settings a session sets from the start (at the optimizer's defaults); the others stay
#: unset, so a method's sensor-set profile supplies them (``engine/solver/profiles.py``).
SESSION_SETTINGS = ("mode", "iterations", "lr", "temporal_weight")


def default_settings() -> SettingsEdit:
    """The optimizer's own defaults of :data:`SESSION_SETTINGS`."""
    d = OptimizerSettings()
    return SettingsEdit({name: getattr(d, name) for name in SESSION_SETTINGS})


def scene_to_dict(
    path: Path | None,
    method: str,
    preset: str,
    sensors: Iterable[Sensor],
    constraints: Iterable[Constraint],
    settings: Mapping[str, Any],
    frame: int,
) -> dict[str, Any]:
    """Plain-JSON description of a session's scene (the clip by path)."""
    doc = optimizer_scene.scene_to_dict(constraints, dict(settings))
    doc.update(
        {
            "clip": str(path) if path else None,
            "method": method,
            "preset": preset,
            "sensors": [s.to_dict() for s in sensors],
            "frame": int(frame),
        }
    )
    return doc


def scene_from_dict(scene: Any, where: str = "scene") -> dict[str, Any]:
    """Check and convert :func:`scene_to_dict` output; errors name ``where`` and the entry.

    Returns a dict with ``method`` (str), ``preset`` (str), ``sensors`` (tuple of
    Sensor), ``constraints`` (list of Constraint), ``settings`` (a :class:`SettingsEdit`
    of the settings the scene gives), ``frame`` (int).
    """
    authored = authoring_from_dict(scene, where)  # also checks it is an object and its constraints
    constraints, settings = authored.constraints, authored.settings
    sensors = scene.get("sensors")
    if sensors is not None:
        if not isinstance(sensors, list):
            raise UserError(f"{where}: field 'sensors' must be a list")
        sensors = tuple(Sensor.from_dict(s, f"{where}: sensors[{i}]") for i, s in enumerate(sensors))
    given = scene.get("settings") or {}
    frame = scene.get("frame")
    if frame is not None and (isinstance(frame, bool) or not isinstance(frame, int) or frame < 0):
        raise UserError(f"{where}: field 'frame' must be a whole number of 0 or more, got {shown(frame)}")
    return {
        "method": str(scene.get("method") or ""),
        "preset": None if scene.get("preset") is None else str(scene["preset"]),
        "sensors": sensors,
        "constraints": constraints,
        "settings": SettingsEdit({k: getattr(settings, k) for k in given}, where),
        "frame": frame,
        "keys": len(authored.keys),
    }


def describe_load(parsed: Mapping[str, Any]) -> str:
    """One line saying what applying ``parsed`` (:func:`scene_from_dict`) replaces and
    keeps, e.g. ``replaced the constraints (2) and settings (lr); kept the sensors and
    preset (the scene has none); its 3 keys are for File > New pose and bake``."""
    n = len(parsed["constraints"])
    replaced = [f"the constraints ({n})" if n else "the constraints (none in the scene)"]
    given = list(parsed["settings"])
    if given:
        replaced.append(
            f"settings ({', '.join(given)})" if len(given) <= 3 else f"the optimizer settings ({len(given)})"
        )
    if parsed["sensors"] is not None:
        replaced.append(f"the sensors ({len(parsed['sensors'])})")
    kept = [] if parsed["sensors"] is not None else ["the sensors and preset (the scene has none)"]
    listed = replaced[0] if len(replaced) == 1 else f"{', '.join(replaced[:-1])} and {replaced[-1]}"
    out = f"replaced {listed}"
    if kept:
        out += f"; kept {', '.join(kept)}"
    if parsed["keys"]:
        out += f"; its {parsed['keys']} key{'s' * (parsed['keys'] != 1)} are for the pose window and bake"
    return out


def apply_scene(session: Any, scene: dict[str, Any], where: str = "scene") -> str:
    """Restore a session's :func:`scene_to_dict` output (the clip is loaded by the caller)
    through its methods; what the scene leaves out (sensors, method, frame) stays as it
    is. Returns a line saying what was replaced and kept (:func:`describe_load`).
    Everything is checked before anything changes; errors name ``where``."""
    parsed = scene_from_dict(scene, where)
    session.set_settings(parsed["settings"])
    if parsed["sensors"] is not None:
        session.sensors.set_all(parsed["sensors"], parsed["preset"] or "")
    session.constraints.set_all(parsed["constraints"])
    if parsed["method"] and parsed["method"] != session.method:
        session.set_method(parsed["method"])
    if parsed["frame"] is not None:
        session.seek(parsed["frame"])
    return describe_load(parsed)
