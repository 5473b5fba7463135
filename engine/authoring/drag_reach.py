"""Where a dragged wrist or ankle goes along the mouse ray: on the drag plane, within reach.

A drag moves a joint on a plane through it that faces the camera: the mouse gives two
coordinates, the plane the third, the depth. The mean pose's wrists hang about 20 cm in
front of the shoulders, so a wrist dragged out sideways in the front view kept that
depth: at the arm's length on screen its target lay beyond the arm's reach, and the
straightened arm pointed 20-45 degrees forward of where the user had put it.

:func:`on_reach` keeps what the user sees (a point on the same mouse ray) and gives up
only as much of the depth as the limb's reach asks: the plane's point while the limb
reaches it, else the nearest point of the ray that it reaches, else (the ray passes
beyond the limb's reach) the ray's point nearest the limb's root, which the straightened
limb points at. It is a function of the mouse position alone, so dragging back gives the
depth back.
"""

from __future__ import annotations

import numpy as np

from engine import skeleton as sk
from engine.solver.limb_ik import LIMBS

#: Of the limb's length, how far from its root a target is put (a hair inside full
#: stretch, where the exact limb step has no bend left to place the middle joint).
REACH_SHARE = 0.999


def limb_reach(positions: np.ndarray, joint: str) -> tuple[np.ndarray, float] | None:
    """The root (shoulder or hip) ``(3,)`` metres of the limb that ``joint`` ends and
    the limb's length (its two bones) in ``positions (22, 3)``; None for a joint that
    ends no limb (only wrists and ankles do)."""
    c = sk.JOINT_INDEX.get(joint)
    if c not in LIMBS:
        return None
    a, b = LIMBS[c]
    p = np.asarray(positions, float)
    return p[a].copy(), float(np.linalg.norm(p[b] - p[a]) + np.linalg.norm(p[c] - p[b]))


def on_reach(
    point: np.ndarray, origin: np.ndarray, direction: np.ndarray, root: np.ndarray, length: float
) -> np.ndarray:
    """Where a limb end dragged to ``point (3,)`` on its drag plane goes (see the module
    doc): a point ``(3,)`` metres of the mouse ray ``origin + t * direction`` within
    :data:`REACH_SHARE` of ``length`` metres of ``root (3,)`` when the ray passes that
    close, else the ray's point nearest to ``root``."""
    p = np.asarray(point, float)
    o, d, r = np.asarray(origin, float), np.asarray(direction, float), np.asarray(root, float)
    reach = REACH_SHARE * float(length)
    if np.linalg.norm(p - r) <= reach:
        return p.copy()
    dd = float(d @ d)
    if dd < 1e-18:
        return p.copy()
    t_near = float((r - o) @ d) / dd  # the ray's point nearest the root
    miss = float(np.linalg.norm(o + t_near * d - r))
    if miss >= reach:
        return o + t_near * d
    half = np.sqrt(reach * reach - miss * miss) / np.sqrt(dd)
    t_point = float((p - o) @ d) / dd
    # of the two points where the ray enters and leaves the reach, the one nearer the plane's
    t = t_near - half if abs(t_near - half - t_point) <= abs(t_near + half - t_point) else t_near + half
    return o + t * d
