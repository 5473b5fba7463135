"""The session's scene files: sensors, constraints, optimizer settings as plain JSON."""

from __future__ import annotations

import dataclasses
from collections.abc import Iterable
from pathlib import Path
from typing import Any

from engine.constraints.base import Constraint, from_dict
from engine.errors import UserError
from engine.optimizer import OptimizerSettings
from engine.sensors import Sensor


def default_settings() -> dict[str, Any]:
    """The optimizer's own defaults the panel starts from (one source of truth)."""
    d = OptimizerSettings()
    return {"mode": d.mode, "iterations": d.iterations, "lr": d.lr, "temporal_weight": d.temporal_weight}


def scene_to_dict(path: Path | None, method: str, preset: str, sensors: Iterable[Sensor],
                  constraints: Iterable[Constraint], settings: dict[str, Any], frame: int) -> dict[str, Any]:  # fmt: skip
    """Plain-JSON description of a session's scene (the clip by path)."""
    return {
        "clip": str(path) if path else None,
        "method": method,
        "preset": preset,
        "sensors": [s.to_dict() for s in sensors],
        "constraints": [c.to_dict() for c in constraints],
        "settings": dict(settings),
        "frame": int(frame),
    }


def scene_from_dict(scene: Any, where: str = "scene") -> dict[str, Any]:
    """Check and convert :func:`scene_to_dict` output; errors name ``where`` and the entry.

    Returns a dict with ``method`` (str), ``preset`` (str), ``sensors`` (tuple of
    Sensor), ``constraints`` (list of Constraint), ``settings`` (dict), ``frame`` (int).
    """
    if not isinstance(scene, dict):
        raise UserError(f"{where}: expected a JSON object")
    sensors = tuple(Sensor.from_dict(s, f"{where}: sensors[{i}]") for i, s in enumerate(scene.get("sensors", [])))
    constraints = []
    for i, c in enumerate(scene.get("constraints", [])):
        try:
            constraints.append(from_dict(dict(c) if isinstance(c, dict) else c))
        except UserError as exc:
            raise UserError(f"{where}: constraints[{i}]: {exc}") from exc
    settings = scene.get("settings", {})
    if not isinstance(settings, dict):
        raise UserError(f"{where}: field 'settings' must be an object")
    known = {f.name for f in dataclasses.fields(OptimizerSettings)}
    unknown = sorted(set(settings) - known)
    if unknown:
        raise UserError(f"{where}: settings: unknown field(s) {', '.join(unknown)}")
    try:
        frame = int(scene.get("frame", 0))
    except (TypeError, ValueError):
        raise UserError(f"{where}: field 'frame' must be an integer") from None
    return {"method": str(scene.get("method") or ""), "preset": str(scene.get("preset") or ""),
            "sensors": sensors, "constraints": constraints, "settings": dict(settings), "frame": frame}  # fmt: skip
