"""Where a new constraint starts: next to the character as it stands, not at the origin.

The engine's defaults are fixed numbers (a bounds box at the origin, a look-at target at
(0, -2, 1.6)); once the clip has walked a few metres they are far off screen. Given the
pose on screen, :func:`placed_params` returns the parameters that put a new constraint
where it is visible and already (nearly) satisfied, so the user starts from something
they can see and drag.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np

from engine import skeleton as sk

BOUNDS_HALF = np.array([0.4, 0.4, 0.3])  # metres around the joint
LOOK_DISTANCE = 1.5  # metres in front of the head
REACH = 0.15  # metres: an end-effector target starts this far in front of its joint


def facing(positions: np.ndarray) -> np.ndarray:
    """Horizontal unit vector the body faces, from the hips ``(22, 3)`` (rest pose: -Y)."""
    across = positions[sk.JOINT_INDEX["lhip"]] - positions[sk.JOINT_INDEX["rhip"]]  # towards the left (+X at rest)
    forward = np.cross(np.array([0.0, 0.0, 1.0]), across)  # z x (+X) = +Y; the body faces -Y
    forward = -forward[:2]
    norm = np.linalg.norm(forward)
    return np.array([0.0, -1.0, 0.0]) if norm < 1e-6 else np.r_[forward / norm, 0.0]


def _joint(p: np.ndarray, name: Any, fallback: str) -> np.ndarray:
    return p[sk.JOINT_INDEX.get(str(name), sk.JOINT_INDEX[fallback])]


def _bounds(p: np.ndarray, d: dict) -> dict:
    c = _joint(p, d.get("joint"), "root")
    return {"box_min": c - BOUNDS_HALF, "box_max": c + BOUNDS_HALF}


def _look_at(p: np.ndarray, d: dict) -> dict:
    head = _joint(p, d.get("joint"), "upperneck")
    return {"target": head + LOOK_DISTANCE * facing(p)}


def _reach(field: str) -> Callable[[np.ndarray, dict], dict]:
    def place(p: np.ndarray, d: dict) -> dict:
        return {field: _joint(p, d.get("joint"), "lwrist") + REACH * facing(p)}

    return place


def _pin(p: np.ndarray, d: dict) -> dict:
    return {"position": _joint(p, d.get("joint"), "lankle").copy()}


def _distance(p: np.ndarray, d: dict) -> dict:
    a, b = _joint(p, d.get("joint_a"), "lwrist"), _joint(p, d.get("joint_b"), "rwrist")
    return {"distance": float(np.linalg.norm(a - b))}


_PLACERS: dict[str, Callable[[np.ndarray, dict], dict]] = {
    "bounds": _bounds, "look_at": _look_at, "end_effector": _reach("position"),
    "pin": _pin, "distance": _distance,
}  # fmt: skip


def placed_params(kind: str, defaults: dict[str, Any], positions: np.ndarray | None) -> dict[str, Any]:
    """Parameters of a new ``kind`` constraint placed on the pose ``positions`` (22, 3) m.

    Only fields the kind has are returned; with no (finite) pose, nothing is changed.
    """
    place = _PLACERS.get(kind)
    if place is None or positions is None or not np.all(np.isfinite(positions)):
        return {}
    out = place(np.asarray(positions, float), defaults)
    return {k: v for k, v in out.items() if k in defaults}
