"""Where the studio puts a new constraint: next to the character as it stands, in view.

The kinds' defaults are fixed numbers (a bounds box at the origin, a look-at target at
(0, -2, 1.6)); once a clip has walked a few metres they are far off screen. Each kind's
:meth:`~engine.constraints.base.Constraint.placement` uses these helpers to move its
points onto the pose on screen, close enough to the body that every camera preset of the
viewport (framed on the hips) shows them.
"""

from __future__ import annotations

from collections.abc import Collection
from typing import Any

import numpy as np

from engine import skeleton as sk

#: Half size of a new bounds box around its joint, metres.
BOUNDS_HALF = np.array([0.4, 0.4, 0.3])
#: A new look-at target is this far in front of the head, metres: far enough to read as
#: a direction, near enough to stay in the viewport's 35-degree view from any preset.
LOOK_DISTANCE = 0.8
#: A new end-effector target starts this far in front of its joint, metres.
REACH = 0.15


def facing(positions: np.ndarray) -> np.ndarray:
    """Horizontal unit vector ``(3,)`` the body faces, from the hips of ``positions (22, 3)``
    (the rest pose faces -Y)."""
    across = positions[sk.JOINT_INDEX["lhip"]] - positions[sk.JOINT_INDEX["rhip"]]  # towards the left (+X at rest)
    forward = -np.cross(np.array([0.0, 0.0, 1.0]), across)[:2]  # z x (+X) = +Y; the body faces -Y
    norm = np.linalg.norm(forward)
    return np.array([0.0, -1.0, 0.0]) if norm < 1e-6 else np.r_[forward / norm, 0.0]


def joint_at(positions: np.ndarray, name: Any, fallback: str) -> np.ndarray:
    """Position ``(3,)`` of joint ``name`` (``fallback`` when it is not a joint name), a copy."""
    return np.array(positions[sk.JOINT_INDEX.get(str(name), sk.JOINT_INDEX[fallback])], dtype=np.float64)


def new_joint(default: str, taken: Collection[str] = (), selected: str | None = None) -> str:
    """The joint a new one-joint constraint (a pin, an end-effector target...) goes on.

    The joint selected in the view (a click on it) when there is one, else the kind's
    ``default``, else its mirror (the right ankle after the left one), else the first in
    skeleton order, skipping joints in ``taken``: those a constraint of the same kind
    already holds, where a second one would only duplicate the first. Every joint taken:
    ``default``.
    """
    mirror = dict(sk.MIRROR_PAIRS + tuple((b, a) for a, b in sk.MIRROR_PAIRS))
    order = ([selected] if selected in sk.JOINT_INDEX else []) + [default, mirror.get(default, default)]
    return next((j for j in (*order, *sk.JOINT_NAMES) if j not in taken), default)
