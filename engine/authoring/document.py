"""Authoring scenes (scene format version 2): character, animation, keys, constraints.

Read with :func:`load_authoring` (any scene version: a version-1 scene is a scene with no
animation and no keys), written with :func:`save_authoring` (atomically). Every error
names the file and the field, e.g. ``s.json: keys[1]: targets: lwrist: position must be 3
finite numbers``.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from engine.atomic import write_text
from engine.authoring.keys import PLANTED, SCHEMES, Animation, Key
from engine.authoring.pose_options import PoseOptions, options_from_dict, options_to_dict
from engine.authoring.targets import target_from_json
from engine.constraints.base import Constraint
from engine.errors import UserError
from engine.input_files import read_json
from engine.scene import scene_from_dict, scene_to_dict
from engine.solver import OptimizerSettings
from engine.validation import check_known_fields, shown

#: Longest animation accepted, frames (ten minutes at 60 fps).
MAX_FRAMES = 36000


@dataclass
class AuthoringScene:
    """Everything a scene file says about an authored motion.

    Attributes
    ----------
    constraints : list of Constraint
    settings : OptimizerSettings
    animation : Animation
    keys : list of Key
        Sorted by frame, one per frame.
    height : float or None
        The character's standing height, metres (None: the canonical skeleton's).
    version : int
        The version the file was written in.
    pose_options : PoseOptions
        How pose mode keeps the keys' poses natural when they are posed (the bake, the
        pose window); the defaults when the file gives none.
    """

    constraints: list[Constraint] = field(default_factory=list)
    settings: OptimizerSettings = field(default_factory=OptimizerSettings)
    animation: Animation = field(default_factory=Animation)
    keys: list[Key] = field(default_factory=list)
    height: float | None = None
    version: int = 2
    pose_options: PoseOptions = field(default_factory=PoseOptions)


def load_authoring(path: str | Path) -> AuthoringScene:
    """Read a scene file of any version; errors name the file and the field."""
    path = Path(path)
    return authoring_from_dict(read_json(path, "scene"), str(path))


def authoring_from_dict(doc: Any, where: str = "scene") -> AuthoringScene:
    """Check and convert a scene document (see the module doc)."""
    constraints, settings = scene_from_dict(doc, where)  # format, version, settings, constraints
    out = AuthoringScene(constraints, settings, version=int(doc.get("version", 1)))
    out.height = _height(doc.get("character"), where)
    out.animation = _animation(doc.get("animation"), where)
    if doc.get("pose_options") is not None:
        out.pose_options = options_from_dict(doc["pose_options"], f"{where}: field 'pose_options'")
    raw = doc.get("keys", []) or []
    if not isinstance(raw, list):
        raise UserError(f"{where}: field 'keys' must be a list")
    out.keys = [_key(item, f"{where}: keys[{i}]", out.animation.frames) for i, item in enumerate(raw)]
    frames = [k.frame for k in out.keys]
    dup = sorted({f for f in frames if frames.count(f) > 1})
    if dup:
        raise UserError(f"{where}: keys: more than one key on frame(s) {', '.join(map(str, dup))}")
    out.keys.sort(key=lambda k: k.frame)
    return out


def authoring_to_dict(scene: AuthoringScene) -> dict:
    """Plain-JSON form (version 2)."""
    doc = scene_to_dict(scene.constraints, scene.settings)
    doc["version"] = 2
    if scene.height is not None:
        doc["character"] = {"height": float(scene.height)}
    a = scene.animation
    doc["animation"] = {"fps": float(a.fps), "frames": int(a.frames), "interpolation": a.interpolation}
    doc["keys"] = [k.to_dict() for k in scene.keys]
    options = options_to_dict(scene.pose_options)
    if options:
        doc["pose_options"] = options
    return doc


def save_authoring(path: str | Path, scene: AuthoringScene) -> None:
    """Write ``scene`` to ``path`` as JSON, atomically."""
    write_text(path, json.dumps(authoring_to_dict(scene), indent=2, allow_nan=False) + "\n")


def _number(value: Any, where: str, lo: float, hi: float) -> float:
    if (
        isinstance(value, bool)
        or not isinstance(value, (int, float))
        or not math.isfinite(value)
        or not lo <= value <= hi
    ):
        raise UserError(f"{where} must be a number in {lo:g}-{hi:g}, got {shown(value)}")
    return float(value)


def _whole(value: Any, where: str, lo: int, hi: int) -> int:
    if isinstance(value, float) and value.is_integer():
        value = int(value)
    if isinstance(value, bool) or not isinstance(value, int) or not lo <= value <= hi:
        raise UserError(f"{where} must be a whole number in {lo}-{hi}, got {shown(value)}")
    return value


def _object(value: Any, where: str, fields: set[str]) -> dict:
    if not isinstance(value, dict):
        raise UserError(f"{where} must be an object")
    check_known_fields(value, fields, where)
    return value


def _height(value: Any, where: str) -> float | None:
    if value is None:
        return None
    value = _object(value, f"{where}: field 'character'", {"height"})
    return None if "height" not in value else _number(value["height"], f"{where}: character: field 'height'", 0.5, 2.5)


def _animation(value: Any, where: str) -> Animation:
    if value is None:
        return Animation()
    value = _object(value, f"{where}: field 'animation'", {"fps", "frames", "interpolation"})
    a = Animation()
    if "fps" in value:
        a.fps = _number(value["fps"], f"{where}: animation: field 'fps'", 1.0, 240.0)
    if "frames" in value:
        a.frames = _whole(value["frames"], f"{where}: animation: field 'frames'", 1, MAX_FRAMES)
    if "interpolation" in value:
        if value["interpolation"] not in SCHEMES:
            raise UserError(
                f"{where}: animation: field 'interpolation' is {shown(value['interpolation'])}; "
                f"choose {', '.join(SCHEMES)}"
            )
        a.interpolation = value["interpolation"]
    return a


def _key(value: Any, where: str, frames: int) -> Key:
    value = _object(value, where, {"frame", "targets", "latent", "root", "heading", "feet"})
    if "frame" not in value:
        raise UserError(f"{where}: field 'frame' is missing")
    key = Key(_whole(value["frame"], f"{where}: field 'frame'", 0, frames - 1))
    targets = value.get("targets", {}) or {}
    if not isinstance(targets, dict):
        raise UserError(f"{where}: field 'targets' must be an object (joint -> [x, y, z])")
    key.targets = {j: target_from_json(j, t, f"{where}: targets: {j}") for j, t in targets.items()}
    if value.get("latent") is not None:
        key.latent = _vector(value["latent"], f"{where}: field 'latent'", None).astype(np.float32)
    if "root" in value:
        key.root = _vector(value["root"], f"{where}: field 'root'", 2)
    if "heading" in value:
        key.heading = _number(value["heading"], f"{where}: field 'heading'", -360.0, 360.0)
    if value.get("feet") is not None:
        feet = _object(value["feet"], f"{where}: field 'feet'", set(PLANTED))
        key.feet = {j: _vector(p, f"{where}: feet: field {j!r}", 3) for j, p in feet.items()}
    return key


def _vector(value: Any, where: str, n: int | None) -> np.ndarray:
    ok = isinstance(value, list) and all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in value)
    a = np.asarray(value, dtype=np.float64) if ok else np.zeros(0)
    if not ok or (n is not None and a.size != n) or a.size == 0 or not np.isfinite(a).all():
        raise UserError(f"{where} must be a list of {n or 'some'} finite numbers")
    return a
