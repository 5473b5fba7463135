"""The constraint kinds users may add in the studio, with their editable fields.

Built from :data:`engine.constraints.REGISTRY`: every kind whose class has
``user_facing`` set (methods build ``sensor`` and ``temporal_prior`` themselves). Each
field gets a tag an editor can switch on (``float``, ``int``, ``bool``, ``joint``,
``choice``, ``str``, ``vec3``), its default and, for ``choice``, the accepted values.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from typing import Any

import numpy as np

import engine.constraints  # noqa: F401  (importing the package registers every kind)
from engine.constraints.base import REGISTRY, Constraint, field_default

#: Fields every constraint has; editors show them apart from the kind's parameters.
COMMON_FIELDS = ("name", "weight", "enabled")


@dataclass(frozen=True)
class FieldSpec:
    """One editable parameter of a constraint kind (``default`` in the field's unit:
    metres for positions and distances, degrees for angles)."""

    name: str
    tag: str
    default: Any
    choices: tuple[str, ...] = ()


@dataclass(frozen=True)
class ConstraintKind:
    """A user-facing constraint kind: its ``kind`` string, fields and one-line summary."""

    kind: str
    fields: tuple[FieldSpec, ...]
    summary: str
    cls: type[Constraint]

    def field(self, name: str) -> FieldSpec | None:
        return next((f for f in self.fields if f.name == name), None)


def _tag(cls: type[Constraint], name: str, default: Any) -> str:
    if name in cls.choices:
        return "choice"
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


def describe(cls: type[Constraint]) -> ConstraintKind:
    """The catalog entry of one constraint class."""
    fields = []
    for f in dataclasses.fields(cls):
        if f.name in COMMON_FIELDS or not f.init:
            continue
        d = field_default(f)
        fields.append(FieldSpec(f.name, _tag(cls, f.name, d), d, tuple(cls.choices.get(f.name, ()))))
    summary = (cls.__doc__ or cls.kind).strip().splitlines()[0]
    return ConstraintKind(cls.kind, tuple(fields), summary, cls)


def constraint_catalog() -> dict[str, ConstraintKind]:
    """Every user-facing kind by name, sorted by name."""
    return {k: describe(c) for k, c in sorted(REGISTRY.items()) if c.user_facing}
