"""Constraint kinds of the pose optimizer; importing this package registers them all.

Every module of this package that is not part of the interface (``base``, ``residual``,
``placement``) defines one kind: a :class:`~engine.constraints.base.Constraint`
subclass with a ``kind`` string. The package imports each such module, so adding a kind
means adding its module (and its test), nothing here. A module that fails to import, or
a kind that lacks a part (:func:`~engine.constraints.base.missing_parts`), fails the
import of the package with an error naming it. Each kind's class is also an attribute
of the package (``engine.constraints.PinConstraint``).

See :mod:`engine.constraints.base` for the interface and ``docs/optimizer.md`` for the
parameters of every kind.
"""

from __future__ import annotations

import importlib
import pkgutil
from typing import Any

from engine.constraints.base import REGISTRY, Constraint, from_dict

#: Modules of the package that define the interface, not a kind.
INTERFACE_MODULES = ("base", "residual", "placement")


def _discover() -> dict[str, type[Constraint]]:
    """Import every kind module of the package; class name -> class of each kind."""
    for info in sorted(pkgutil.iter_modules(__path__), key=lambda m: m.name):
        if info.name in INTERFACE_MODULES or info.name.startswith("_"):
            continue
        try:
            importlib.import_module(f"{__name__}.{info.name}")
        except Exception as exc:  # a broken kind must not vanish from the studio silently
            raise ImportError(f"constraint kind module {__name__}.{info.name} failed to import: {exc}") from exc
    for cls in REGISTRY.values():
        cls.check_complete()
    return {cls.__name__: cls for cls in REGISTRY.values()}


_KINDS = _discover()
globals().update(_KINDS)


def __getattr__(name: str) -> Any:
    """``PoseState`` (what every ``loss(state)`` receives) on first use, since it imports
    torch, which the studio's window never needs; kinds registered after the import (e.g.
    by a plug-in module) by class name."""
    if name == "PoseState":
        from engine.kinematics.pose_state import PoseState

        return PoseState
    for cls in REGISTRY.values():
        if cls.__name__ == name:
            return cls
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


__all__ = ["REGISTRY", "Constraint", "PoseState", "from_dict", *sorted(_KINDS)]
