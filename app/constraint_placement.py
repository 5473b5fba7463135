"""Where a new constraint starts: next to the character as it stands, not at the origin.

Each kind says where it goes (:meth:`engine.constraints.base.Constraint.placement`, with
the helpers of :mod:`engine.constraints.placement`); this module applies that rule to the
pose on screen, so the user starts from something visible and already (nearly) satisfied.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Collection
from typing import Any

import numpy as np

from engine.constraints import REGISTRY
from engine.constraints.base import OnOneJoint
from engine.constraints.placement import facing, new_joint

__all__ = ["facing", "moved_params", "placed_params"]


def placed_params(
    kind: str,
    defaults: dict[str, Any],
    positions: np.ndarray | None,
    selected: str | None = None,
    taken: Collection[str] = (),
) -> dict[str, Any]:
    """Parameters of a new ``kind`` constraint placed on the pose ``positions`` (22, 3) m.

    A kind on one joint (a pin, an end-effector target...) goes on the joint
    ``selected`` in the view, else on a joint no constraint of its kind holds yet
    (``taken``; :func:`engine.constraints.placement.new_joint`), so pins added one
    after another do not pile up on the default ankle. Only fields the kind has are
    returned; with no (finite) pose, or an unknown kind, nothing is placed.
    """
    cls = REGISTRY.get(kind)
    if cls is None:
        return {}
    params = dict(defaults)
    chosen: dict[str, Any] = {}
    if issubclass(cls, OnOneJoint) and "joint" in params:
        joint = new_joint(str(params["joint"]), taken, selected)
        if joint != params["joint"]:
            params["joint"] = chosen["joint"] = joint
    if positions is None or not np.all(np.isfinite(positions)):
        return chosen
    out = chosen | cls.placement(params, np.asarray(positions, float))
    return {k: v for k, v in out.items() if k in defaults}


def moved_params(constraint: Any, changes: dict[str, Any], positions: np.ndarray | None) -> dict[str, Any]:
    """``changes`` to ``constraint`` (a :class:`engine.constraints.base.Constraint`) plus,
    when they put it on other joints (a ``joint`` or ``joints`` field) and set none of the
    fields its placement gives, those fields placed on the pose ``positions`` (22, 3) m
    for the new joints: a pin moved from the ankle to the elbow is pinned where the elbow
    is, not left at the ankle's place, where it pulls the elbow down to the floor."""
    cls = REGISTRY.get(constraint.kind)
    editors = {f.name: f.metadata.get("editor") for f in dataclasses.fields(constraint)}
    moved = any(editors.get(k) in ("joint", "joints") for k in changes)
    if cls is None or not moved or positions is None or not np.all(np.isfinite(positions)):
        return changes
    params = {k: getattr(constraint, k) for k in editors} | changes
    placed = cls.placement(params, np.asarray(positions, float))
    if any(k in changes for k in placed):
        return changes
    return changes | {k: v for k, v in placed.items() if k in editors}
