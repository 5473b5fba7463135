"""Constraints: every tracker, target and rule the pose optimizer satisfies is one.

A constraint is a small dataclass with its parameters, a ``weight`` and an ``enabled``
flag, and a differentiable :meth:`Constraint.loss` of the current :class:`PoseState`.
The optimizer sums ``weight * loss`` over enabled constraints. Parameters can change
between frames (the GUI does this live). Each kind registers itself by its ``kind``
string, so a scene can be saved to JSON and loaded back (:func:`from_dict`).
"""

from __future__ import annotations

import dataclasses
from abc import ABC, abstractmethod
from dataclasses import dataclass
from typing import Any, ClassVar

import numpy as np
import torch

from engine.errors import UserError

#: kind string -> constraint class; filled by subclasses as they are defined.
REGISTRY: dict[str, type["Constraint"]] = {}


@dataclass
class PoseState:
    """The decoded pose a constraint judges (torch, differentiable w.r.t. the latent).

    Attributes
    ----------
    positions : Tensor (22, 3)
        World joint positions, metres (Z-up, floor at z = 0).
    rotations : Tensor (22, 4)
        World joint rotations (w, x, y, z).
    local_rot : Tensor (22, 4)
        Local joint rotations; row 0 is the root's world rotation.
    latent : Tensor (L,)
        The latent vector being optimised.
    previous_positions : Tensor (22, 3) or None
        The previous frame's solved positions (for pins and foot contact).
    frame : int
        Frame index in the clip.
    """

    positions: torch.Tensor
    rotations: torch.Tensor
    local_rot: torch.Tensor
    latent: torch.Tensor
    previous_positions: torch.Tensor | None = None
    frame: int = 0


@dataclass
class Constraint(ABC):
    """Base class. Subclasses are dataclasses whose extra fields are their parameters."""

    kind: ClassVar[str] = ""
    #: Human label shown in the GUI and loss plots (unique within a scene).
    name: str = ""
    weight: float = 1.0
    enabled: bool = True

    def __init_subclass__(cls, **kw: Any) -> None:
        super().__init_subclass__(**kw)
        if cls.kind:
            REGISTRY[cls.kind] = cls

    @abstractmethod
    def loss(self, state: PoseState) -> torch.Tensor:
        """Scalar, non-negative; zero when the constraint is satisfied."""

    def satisfied(self, state: PoseState) -> bool:
        """Whether the offline optimizer may stop on this constraint's account."""
        return True

    def gizmo(self) -> dict[str, Any]:
        """Plain-numpy description for the viewport (e.g. ``{"type": "point", "position": ...}``)."""
        return {}

    def to_dict(self) -> dict[str, Any]:
        out: dict[str, Any] = {"kind": self.kind}
        for f in dataclasses.fields(self):
            v = getattr(self, f.name)
            out[f.name] = v.tolist() if isinstance(v, np.ndarray) else v
        return out


def from_dict(data: dict[str, Any]) -> Constraint:
    """Rebuild a constraint saved with :meth:`Constraint.to_dict`; errors name the field."""
    kind = data.get("kind")
    if kind not in REGISTRY:
        raise UserError(f"unknown constraint kind {kind!r}; known: {', '.join(sorted(REGISTRY))}")
    cls = REGISTRY[kind]
    names = {f.name: f for f in dataclasses.fields(cls)}
    kwargs = {}
    for key, value in data.items():
        if key == "kind":
            continue
        if key not in names:
            raise UserError(f"constraint {kind!r}: unknown field {key!r}")
        default = names[key].default
        if isinstance(default, np.ndarray) or (
            names[key].default_factory is not dataclasses.MISSING  # type: ignore[misc]
            and isinstance(names[key].default_factory(), np.ndarray)  # type: ignore[misc]
        ):
            value = np.asarray(value, dtype=float)
        kwargs[key] = value
    try:
        return cls(**kwargs)
    except (TypeError, ValueError) as exc:
        raise UserError(f"constraint {kind!r}: {exc}") from exc
