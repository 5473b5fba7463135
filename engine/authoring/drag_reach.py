"""Where a dragged wrist or ankle goes along the mouse ray: the depth its limb stretches to.

A drag moves a joint on a plane through it that faces the camera: the mouse gives two
coordinates on screen, the plane the third, the depth. The mean pose's wrists hang about
20 cm in front of the shoulders, so a wrist dragged out sideways in the front view kept
that depth, and a T-pose made there ended with the arms 25-45 degrees forward: the
wrist sat under the mouse, but at the depth it had hung at.

:func:`on_reach` keeps what the user sees (a point on the same mouse ray) and picks the
depth by how far the limb is stretched on the drag plane. Measured from the limb's root
(shoulder, hip) along the plane's normal, the depth ``d`` is the pressed point's ``d0``
while the point is no further from the root across the plane than at the press
(``r <= r0``); beyond, it shrinks in step with ``r`` to 0 at the limb's length ``L``,
``d0 * (L - r) / (L - r0)``: the point stays within reach all the way (``r² + d²`` is
convex in ``r``, at most ``L²`` at both ends), and a limb stretched out on screen lies
in the plane of its root, as a user drawing a T-pose in the front view means. Past
``L`` the point is in that plane, and the straight limb points at it. A function of
the mouse position alone: dragging back gives the depth back.
"""

from __future__ import annotations

import numpy as np

from engine import skeleton as sk
from engine.solver.limb_ik import LIMBS

#: Bisection rounds that find the point of the mouse ray at the depth its own distance
#: across the plane asks for (2^-40 of the way from the press's depth to the root's).
ROUNDS = 40


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


def stretched_depth(across: float, across0: float, depth0: float, length: float) -> float:
    """The depth (metres from the root along the plane's normal) for a point ``across``
    metres from the root across the plane, pressed at ``across0`` and ``depth0`` (see the
    module doc); ``depth0`` when the press was beyond the limb's ``length``."""
    if across <= across0 or length <= across0:
        return depth0
    return depth0 * max(0.0, length - across) / (length - across0)


def on_reach(
    point: np.ndarray,
    pressed: np.ndarray,
    origin: np.ndarray,
    direction: np.ndarray,
    normal: np.ndarray,
    root: np.ndarray,
    length: float,
) -> np.ndarray:
    """Where a limb end pressed at ``pressed (3,)`` and dragged to ``point (3,)`` on its
    drag plane (normal ``normal (3,)``) goes: the point ``(3,)`` metres of the mouse ray
    ``origin + t * direction`` at the depth :func:`stretched_depth` gives, for a limb of
    ``length`` metres from ``root (3,)``."""
    n = np.asarray(normal, float)
    n = n / max(float(np.linalg.norm(n)), 1e-12)
    o, d, r = np.asarray(origin, float), np.asarray(direction, float), np.asarray(root, float)
    if abs(float(d @ n)) < 1e-9:  # a ray along the plane: no depth to choose
        return np.asarray(point, float).copy()

    def split(x: np.ndarray) -> tuple[float, float]:
        v = x - r
        depth = float(v @ n)
        return depth, float(np.linalg.norm(v - depth * n))

    depth0, across0 = split(np.asarray(pressed, float))

    def at_depth(depth: float) -> np.ndarray:
        return o + float((r + depth * n - o) @ n) / float(d @ n) * d

    def excess(depth: float) -> float:
        """How much deeper than asked the ray's point at ``depth`` is (towards ``depth0``)."""
        return (depth - stretched_depth(split(at_depth(depth))[1], across0, depth0, float(length))) * np.sign(depth0)

    # the asked depth lies between 0 and depth0: at depth0 the point is at least as deep
    # as asked, in the root's plane no deeper
    lo, hi = 0.0, depth0
    if excess(hi) <= 0.0:
        return at_depth(hi)
    for _ in range(ROUNDS):
        mid = 0.5 * (lo + hi)
        if excess(mid) > 0.0:
            hi = mid
        else:
            lo = mid
    return at_depth(0.5 * (lo + hi))
