"""Describe the session's constraint kinds and optimizer settings as plain editor schemas."""

from __future__ import annotations

from typing import Any

from engine.editing.catalog import constraint_catalog
from widgets.optimizer_panel import SettingField


def _editor_field(f: Any) -> tuple[Any, ...]:
    """One catalog field as the panel's ``(name, tag, default[, choices])``."""
    if f.tag == "choice":
        return (f.name, "choice", f.default, tuple(f.choices))
    if f.tag == "joints":
        return (f.name, "joints", tuple(f.default))  # e.g. the floor's feet
    return (f.name, f.tag, f.default)


def constraint_schema() -> dict[str, list[tuple[Any, ...]]]:
    """kind -> [(field, tag, default[, choices])] for :class:`widgets.constraint_panel.ConstraintPanel`,
    from the session's catalog of user-facing kinds (so ``sensor`` and ``temporal_prior``,
    which methods build themselves, are not offered)."""
    return {kind: [_editor_field(f) for f in spec.fields] for kind, spec in constraint_catalog().items()}


def optimizer_fields() -> tuple[SettingField, ...]:
    """The optimizer panel's fields, in order: the :class:`engine.solver.OptimizerSettings`
    fields whose metadata marks them for the panel, with their labels, help, defaults,
    ranges and choices as the engine validates them (plain data: the widgets need no torch)."""
    from engine.solver import settings as schema
    from engine.validation import Choice, Flag

    out = []
    for f, info in schema.fields():
        if not info.panel:
            continue
        spec, common = info.spec, {"name": f.name, "label": info.label, "default": f.default, "help": info.help}
        if isinstance(spec, Choice):
            out.append(SettingField(kind="choice", choices=tuple(info.offered or spec.options), **common))
        elif isinstance(spec, Flag):
            out.append(SettingField(kind="bool", **common))
        else:
            out.append(
                SettingField(
                    kind="int" if spec.integer else "float",
                    lo=spec.lo,
                    hi=spec.hi,
                    open_lo=spec.open_lo,
                    step=info.step,
                    unit=spec.unit,
                    **common,
                )
            )
    return tuple(out)
