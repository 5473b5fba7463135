"""The constraint kinds users may add (in the studio and the pose window), with their editable fields.

Built from :data:`engine.constraints.REGISTRY`: every kind whose class has
``user_facing`` set (methods build ``sensor`` and ``temporal_prior`` themselves). Each
field gets the editor tag its kind declares on it (``metadata["editor"]``, see
:func:`engine.constraints.base.param`: ``float``, ``int``, ``bool``, ``joint``,
``joints``, ``choice``, ``str``, ``vec3``, ``quat``), its default, unit and, for
``choice``, the accepted values.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from typing import Any

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
    unit: str = ""


@dataclass(frozen=True)
class ConstraintKind:
    """A user-facing constraint kind: its ``kind`` string, fields and one-line summary."""

    kind: str
    fields: tuple[FieldSpec, ...]
    summary: str
    cls: type[Constraint]

    def field(self, name: str) -> FieldSpec | None:
        return next((f for f in self.fields if f.name == name), None)


def describe(cls: type[Constraint]) -> ConstraintKind:
    """The catalog entry of one constraint class (a :class:`TypeError` names what an
    incomplete kind lacks, e.g. editor metadata)."""
    cls.check_complete()
    fields = []
    for f in dataclasses.fields(cls):
        if f.name in COMMON_FIELDS or not f.init:
            continue
        meta = f.metadata
        fields.append(FieldSpec(f.name, meta["editor"], field_default(f), tuple(meta["choices"]), meta["unit"]))
    summary = (cls.__doc__ or cls.kind).strip().splitlines()[0]
    return ConstraintKind(cls.kind, tuple(fields), summary, cls)


def constraint_catalog() -> dict[str, ConstraintKind]:
    """Every user-facing kind by name, sorted by name."""
    return {k: describe(c) for k, c in sorted(REGISTRY.items()) if c.user_facing}
