"""Scenes: a constraint list plus optimizer settings and, from version 2, an authored
animation, as JSON.

Version 1 (``docs/optimizer.md``)::

    {"format": "dragposer-scene", "version": 1,
     "settings": {"mode": "offline", "lr": 0.05, ...},
     "constraints": [{"kind": "look_at", "name": "look", "weight": 1.0, ...}, ...]}

Version 2 (``docs/authoring.md``) adds ``character`` (``height``), ``animation``
(``fps``, ``frames``, ``interpolation``) and ``keys`` (``frame``, ``targets`` by joint,
optional ``latent``, ``root``, ``heading``) and ``pose_options`` (how pose mode poses
the keys: :func:`engine.authoring.pose_options.options_from_dict`); its constraints may carry ``frames`` ranges
(which version 1 files may too: :mod:`engine.constraints.base`). Both versions load; a
scene is written as version 2 only when it has something version 1 lacks.

Every key is checked: an unknown one (top level, settings, constraint fields) is an error
naming the file, the key and the nearest known one, so a misspelt ``keys`` is not read as
"no keys". The studio's own keys (:data:`STUDIO_FIELDS`, written by
:mod:`engine.studio.scenes`) are known here and applied by the studio only. Malformed
constraints are errors naming the file and the field. Files are written atomically
(temporary file, then rename).
"""

from __future__ import annotations

import dataclasses
import json
from collections.abc import Iterable
from pathlib import Path
from typing import Any

import engine.constraints  # noqa: F401  (registers every kind)
from engine.atomic import write_text
from engine.constraints.base import Constraint, from_dict
from engine.errors import UserError
from engine.input_files import read_json
from engine.solver import OptimizerSettings
from engine.validation import check_known_fields, shown

FORMAT = "dragposer-scene"
#: The newest version this build writes and reads; every version up to it loads.
VERSION = 2
VERSIONS = (1, 2)
#: Top-level keys of every scene: the optimizer's (version 1), the authored animation's
#: (version 2), and the studio's own (:mod:`engine.studio.scenes` writes and applies them).
OPTIMIZER_FIELDS = ("format", "version", "settings", "constraints")
AUTHORING_FIELDS = ("character", "animation", "keys", "pose_options")
STUDIO_FIELDS = ("clip", "method", "preset", "sensors", "frame")
SCENE_FIELDS = OPTIMIZER_FIELDS + AUTHORING_FIELDS + STUDIO_FIELDS


def scene_to_dict(constraints: Iterable[Constraint], settings: OptimizerSettings | dict[str, Any] | None) -> dict:
    """Plain-JSON form of a scene."""
    if isinstance(settings, OptimizerSettings):
        settings = dataclasses.asdict(settings)
    items = [c.to_dict() for c in constraints]
    return {
        "format": FORMAT,
        "version": 2 if any("frames" in c for c in items) else 1,
        "settings": dict(settings or {}),
        "constraints": items,
    }


def save_scene(
    path: str | Path, constraints: Iterable[Constraint], settings: OptimizerSettings | dict[str, Any] | None = None
) -> None:
    """Write the scene to ``path`` as JSON (atomically)."""
    doc = scene_to_dict(constraints, settings)
    write_text(path, json.dumps(doc, indent=2, allow_nan=False) + "\n")


def load_scene(path: str | Path) -> tuple[list[Constraint], OptimizerSettings]:
    """Read a scene: its constraints and settings (defaults for settings not given).

    Raises
    ------
    UserError
        Unreadable file, invalid JSON (with line), unknown settings, bad constraints;
        the message names the file and the field.
    """
    path = Path(path)
    doc = read_json(path, "scene")  # regular file, size, UTF-8, depth, number length
    return scene_from_dict(doc, str(path))


def scene_from_dict(doc: Any, where: str = "scene") -> tuple[list[Constraint], OptimizerSettings]:
    """Inverse of :func:`scene_to_dict`; ``where`` prefixes error messages."""
    if not isinstance(doc, dict):
        raise UserError(f"{where}: a scene is a JSON object")
    check_known_fields(doc, SCENE_FIELDS, where)
    if doc.get("format", FORMAT) != FORMAT:
        raise UserError(f"{where}: field 'format' is {shown(doc.get('format'))}, expected {FORMAT!r}")
    version = doc.get("version", 1)
    if isinstance(version, bool) or version not in VERSIONS:
        raise UserError(
            f"{where}: field 'version' is {shown(version)}; this build reads {', '.join(map(str, VERSIONS))}"
        )
    if version < 2:
        late = [k for k in ("animation", "keys", "character", "pose_options") if k in doc]
        if late:
            raise UserError(f'{where}: field {late[0]!r} needs "version": 2')
    raw = doc.get("settings", {}) or {}
    if not isinstance(raw, dict):
        raise UserError(f"{where}: field 'settings' must be an object")
    check_known_fields(raw, (f.name for f in dataclasses.fields(OptimizerSettings)), f"{where}: settings")
    try:
        settings = OptimizerSettings(**raw)
    except UserError as exc:
        raise UserError(f"{where}: settings: {exc}") from exc
    items = doc.get("constraints", []) or []
    if not isinstance(items, list):
        raise UserError(f"{where}: field 'constraints' must be a list")
    constraints = []
    for i, item in enumerate(items):
        try:
            constraints.append(from_dict(item))
        except UserError as exc:
            raise UserError(f"{where}: constraints[{i}]: {exc}") from exc
    names = [c.name for c in constraints]
    dup = sorted({n for n in names if names.count(n) > 1})
    if dup:
        raise UserError(f"{where}: constraints: duplicate name(s) {', '.join(dup)}")
    return constraints, settings
