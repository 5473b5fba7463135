"""A dragged foot does not cross into the other foot: :func:`kept_apart`.

A target dragged on an ankle or a toe joint stops beside the other foot, on the side it
came from, at :data:`GAP` from that foot's line (the two feet's sides touching), while it
is low enough to hit that foot and alongside it: within the dragged foot's length
(ankle to toe tip) of the other foot's stretch from its heel to its toe tip. It passes
freely over the other foot (:data:`CLEAR` above its ankle) and in front of or behind it,
so a crossing step made round the other foot is still the user's to make; straight
through it, a toe dragged onto the other foot would put the two feet in one place. The pose
window's drags (:meth:`engine.authoring.session_pose.PoseEditing.drag_joint`) place
their foot targets with it.
"""

from __future__ import annotations

import numpy as np

from engine import skeleton as sk
from engine.authoring.pose_root import FOOT_OF, TOE_SHARE

#: Least distance (metres) across from the other foot's line (its ankle to its toe, on the
#: floor) to a dragged ankle or toe joint beside it: a foot is about 10 cm wide, so two
#: feet side by side have their lines about that far apart.
GAP = 0.10
#: Height (metres) above the other foot's ankle joint from which a dragged foot joint
#: passes over that foot.
CLEAR = 0.10
#: Of the foot's length from the ankle to the toe joint, how far the heel lies behind
#: the ankle (the heel behind the ankle is about a third of the ankle-to-toe bone).
HEEL_SHARE = 0.35

#: The other foot's ankle and toe joints, by dragged foot joint.
OTHER_FOOT = {j: ("rankle", "rtoe") if FOOT_OF[j] == "l" else ("lankle", "ltoe") for j in FOOT_OF}


def kept_apart(joint: str, position: np.ndarray, positions: np.ndarray, previous: np.ndarray) -> np.ndarray:
    """Where a target dragged on the foot joint ``joint`` to ``position (3,)`` metres goes
    (see the module doc): ``position`` itself, or, where it would lie alongside the other
    foot of ``positions (22, 3)`` metres less than :data:`GAP` across from that foot's
    line on the side of ``previous (3,)`` (where the target or the joint was before this
    move) or beyond it, the point :data:`GAP` across from the line on that side, as far
    along and as high. Joints other than ankles and toes are returned as they are."""
    p = np.asarray(position, float).copy()
    if joint not in OTHER_FOOT:
        return p
    x = np.asarray(positions, float)
    ankle, toe = (x[sk.JOINT_INDEX[j]] for j in OTHER_FOOT[joint])
    if p[2] > ankle[2] + CLEAR:
        return p
    along = np.array([toe[0] - ankle[0], toe[1] - ankle[1], 0.0])
    bone = float(np.linalg.norm(along))
    if bone < 1e-9:
        return p
    along /= bone
    across = np.array([-along[1], along[0], 0.0])
    # the dragged foot's own ankle-to-tip length: how far beyond the other foot they still overlap
    side = FOOT_OF[joint]
    own = x[sk.JOINT_INDEX[f"{side}toe"]] - x[sk.JOINT_INDEX[f"{side}ankle"]]
    length = (1.0 + TOE_SHARE) * float(np.linalg.norm(own[:2]))
    s = float((p - ankle) @ along)
    if not -HEEL_SHARE * bone - length <= s <= (1.0 + TOE_SHARE) * bone + length:
        return p
    came = float((np.asarray(previous, float) - ankle) @ across)
    if abs(came) < 1e-9:  # no side yet: the side the joint is on
        came = float((x[sk.JOINT_INDEX[joint]] - ankle) @ across)
    sign = 1.0 if came >= 0.0 else -1.0
    off = float((p - ankle) @ across) * sign
    if off >= GAP:
        return p
    return p + (GAP - off) * sign * across
