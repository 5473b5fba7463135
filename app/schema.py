"""Describe the engine's constraint kinds as plain editor schemas for the widgets."""

from __future__ import annotations

import dataclasses
import importlib
import pkgutil
from typing import Any

import numpy as np

from engine.constraints.base import field_default

_BASE = ("name", "weight", "enabled")


def load_constraint_kinds() -> dict[str, type]:
    """Import every module of :mod:`engine.constraints` so each kind registers itself."""
    import engine.constraints as pkg
    from engine.constraints.base import REGISTRY

    for info in pkgutil.iter_modules(pkg.__path__):
        try:
            importlib.import_module(f"engine.constraints.{info.name}")
        except Exception:  # a half-written kind must not stop the studio
            continue
    return dict(REGISTRY)


def _tag(name: str, default: Any) -> str:
    if isinstance(default, bool):
        return "bool"
    if isinstance(default, int):
        return "int"
    if isinstance(default, float):
        return "float"
    if isinstance(default, str):
        return "joint" if "joint" in name or name in ("target_joint", "end_effector") else "str"
    if isinstance(default, (np.ndarray, tuple, list)) and np.asarray(default).size == 3:
        return "vec3"
    return "other"


def constraint_schema(kinds: dict[str, type] | None = None) -> dict[str, list[tuple[str, str, Any]]]:
    """kind -> [(field, tag, default)] for :class:`widgets.constraint_panel.ConstraintPanel`."""
    kinds = load_constraint_kinds() if kinds is None else kinds
    out = {}
    for kind, cls in kinds.items():
        fields = []
        for f in dataclasses.fields(cls):
            if f.name in _BASE:
                continue
            d = field_default(f)
            fields.append((f.name, _tag(f.name, d), d))
        out[kind] = fields
    return out


#: Anchors offered for ``root_anchor``: the head tracker, or integrating the decoded root.
ROOT_ANCHORS = ("upperneck", "none")


def optimizer_choices() -> tuple[dict[str, tuple[str, ...]], dict[str, Any]]:
    """Values of the optimizer's choice settings, and every setting's default.

    Only fields :class:`engine.optimizer.OptimizerSettings` really has are offered, so
    the panel never shows a control the engine would reject.

    Returns
    -------
    choices : dict
        ``mode``, ``optimizer`` (the latent update rule) and ``root_anchor`` -> values.
    defaults : dict
        Field name -> default value, shown until the session sets the field.
    """
    from engine import optimizer as opt

    defaults = dataclasses.asdict(opt.OptimizerSettings())
    choices = {"mode": tuple(opt.MODES)}
    if "optimizer" in defaults and hasattr(opt, "OPTIMIZERS"):
        choices["optimizer"] = tuple(opt.OPTIMIZERS)
    if "root_anchor" in defaults:
        anchor = str(defaults["root_anchor"])
        choices["root_anchor"] = ROOT_ANCHORS if anchor in ROOT_ANCHORS else (anchor, *ROOT_ANCHORS)
    return choices, defaults
