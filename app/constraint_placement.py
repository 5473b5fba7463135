"""Where a new constraint starts: next to the character as it stands, not at the origin.

Each kind says where it goes (:meth:`engine.constraints.base.Constraint.placement`, with
the helpers of :mod:`engine.constraints.placement`); this module applies that rule to the
pose on screen, so the user starts from something visible and already (nearly) satisfied.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from engine.constraints import REGISTRY
from engine.constraints.placement import facing

__all__ = ["facing", "placed_params"]


def placed_params(kind: str, defaults: dict[str, Any], positions: np.ndarray | None) -> dict[str, Any]:
    """Parameters of a new ``kind`` constraint placed on the pose ``positions`` (22, 3) m.

    Only fields the kind has are returned; with no (finite) pose, or an unknown kind,
    nothing is changed.
    """
    cls = REGISTRY.get(kind)
    if cls is None or positions is None or not np.all(np.isfinite(positions)):
        return {}
    out = cls.placement(dict(defaults), np.asarray(positions, float))
    return {k: v for k, v in out.items() if k in defaults}
