"""Where a dragged wrist or ankle goes along the mouse ray: the depth of a long drag.

A drag moves a joint on a plane through it that faces the camera: the mouse gives two
coordinates on screen, the plane the third, the depth. The mean pose's wrists hang about
20 cm in front of the shoulders, so a wrist dragged out sideways in the front view at the
depth it hangs at makes a T-pose with the arms 20-45 degrees forward: the wrist is under
the mouse, but at a depth the front view does not show (and the elbow bent towards the
camera looks straight from there).

:func:`on_reach` keeps what the user sees (a point on the same mouse ray) and lets the
depth follow the drag's length. Measured from the limb's root (shoulder, hip) along the
plane's normal, the depth is the pressed point's ``d0`` at the press and fades in step
with how far the point has been dragged across the plane, ``D``, to the root's own
plane once ``D`` reaches :data:`FADE` of the limb's length ``L``:
``d = d0 * max(0, 1 - D / (FADE L))``. A small adjustment keeps the depth nearly as it
was; a drag across the screen, such as from hanging to a T-pose, puts the limb in the
plane of its root, where the view shows it.
The depth is then cut to the limb's reach where it would leave the point beyond it
(``d² <= L² - r²``, ``r`` the point's distance from the root across the plane), so the
limb reaches the point wherever it can. A function of the mouse position alone:
dragging back gives the depth back.
"""

from __future__ import annotations

import numpy as np

from engine import skeleton as sk
from engine.solver.limb_ik import LIMBS

#: Of the limb's length, the drag after which the depth is the root's (a wrist hanging
#: at 0.71 of its arm's length from the shoulder and dragged out to a T-pose travels 0.9
#: of it; one stopped at 0.8 of the straight arm's reach, where the arm bent towards the
#: camera already looks straight from the front, 0.75).
FADE = 0.75
#: How near (metres) the mouse ray must pass another joint of the body for a dragged
#: wrist or ankle to take that joint's depth (:func:`onto_body`): about a joint's drawn
#: sphere and the bone around it.
TOUCH = 0.06
#: Joints a dragged ankle never lands on (:func:`onto_body`), besides its own leg: its toe,
#: which moves with it, and the other foot, which it cannot stand on. In the side view
#: the feet are drawn over each other, and a foot stepped forward along the floor passes
#: over the other foot's toe: taking that toe's depth would cross the feet.
NOT_TOUCHED = {
    "lankle": ("ltoe", "rankle", "rtoe"),
    "rankle": ("rtoe", "lankle", "ltoe"),
}
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


def dragged_depth(dragged: float, across: float, depth0: float, length: float, within: bool = True) -> float:
    """The depth (metres from the root along the plane's normal) of a point ``dragged``
    metres across the plane from the press, ``across`` metres from the root across it,
    pressed at depth ``depth0``, for a limb of ``length`` metres (see the module doc);
    ``within``: the press was within the limb's reach (a target already beyond it is not
    pulled in by the first move)."""
    depth = depth0 * max(0.0, 1.0 - dragged / (FADE * length))
    if not within:
        return depth
    room = float(np.sqrt(max(0.0, length * length - across * across)))
    return float(np.clip(depth, -room, room))


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
    drag plane (normal ``normal (3,)``) goes: the point ``(3,)`` metres of the line
    ``origin + t * direction`` (the mouse ray, or its parallel through ``point``: what
    stays under the cursor) at the depth :func:`dragged_depth` gives, for a limb of
    ``length`` metres from ``root (3,)``."""
    n = np.asarray(normal, float)
    n = n / max(float(np.linalg.norm(n)), 1e-12)
    o, d, r = np.asarray(origin, float), np.asarray(direction, float), np.asarray(root, float)
    if abs(float(d @ n)) < 1e-9:  # a ray along the plane: no depth to choose
        return np.asarray(point, float).copy()

    def split(x: np.ndarray) -> tuple[float, np.ndarray]:
        v = x - r
        depth = float(v @ n)
        return depth, v - depth * n

    depth0, across0 = split(np.asarray(pressed, float))
    within = depth0 * depth0 + float(across0 @ across0) <= length * length * (1.0 + 1e-9)

    def wanted(x: np.ndarray) -> float:
        across = split(x)[1]
        dragged = float(np.linalg.norm(across - across0))
        return dragged_depth(dragged, float(np.linalg.norm(across)), depth0, length, within)

    def at_depth(depth: float) -> np.ndarray:
        return o + float((r + depth * n - o) @ n) / float(d @ n) * d

    def excess(depth: float) -> float:
        """How much deeper than asked the ray's point at ``depth`` is (towards ``depth0``)."""
        return (depth - wanted(at_depth(depth))) * np.sign(depth0)

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


def onto_body(
    point: np.ndarray, direction: np.ndarray, positions: np.ndarray, joint: str, radius: float = TOUCH
) -> np.ndarray | None:
    """A dragged wrist or ankle put onto the body: where the line through ``point (3,)``
    along ``direction (3,)`` (the mouse ray: what stays under the cursor) passes nearest
    a joint of ``positions (22, 3)`` metres within ``radius`` metres, the point of that
    line level with the joint in depth (its closest approach); None when it passes none.

    The joints of the dragged limb (its root, middle joint and end) are left out, and for
    an ankle its toe and the other foot (:data:`NOT_TOUCHED`). A hand dragged onto the
    opposite knee in the front view lands on the knee, not in the plane it hung in 10-15
    cm in front of it, which the front view cannot show."""
    c = sk.JOINT_INDEX.get(joint)
    if c not in LIMBS:
        return None
    d = np.asarray(direction, float)
    d = d / max(float(np.linalg.norm(d)), 1e-12)
    p0 = np.asarray(point, float)
    skip = {c, *LIMBS[c], *(sk.JOINT_INDEX[j] for j in NOT_TOUCHED.get(joint, ()))}
    v = np.asarray(positions, float) - p0
    t = v @ d
    gap = np.linalg.norm(v - t[:, None] * d, axis=1)
    gap[list(skip)] = np.inf
    k = int(np.argmin(gap))
    if gap[k] > radius:
        return None
    return p0 + t[k] * d
