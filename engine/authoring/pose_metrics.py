"""How plausible one posed body is: joint limits, balance, trunk tilt (the pose-mode
benchmark's per-pose measures; :mod:`engine.authoring.pose_reference` adds naturalness).

Every measure reads a pose as local rotations ``(22, 4)``, a root position ``(3,)`` and
the skeleton's bone offsets ``(22, 3)`` (metres, Z up, the floor at z = 0):

* **Flexion** of a knee or elbow: the signed angle, in the limb's bending plane, from the
  upper bone's direction to the lower bone's (0 = straight, positive = bent the way the
  joint bends). The plane is read in the upper bone's own frame (so it turns and twists
  with the thigh or upper arm): it holds the upper bone and the direction the hinge
  moves the lower bone, ``hinge x upper bone``, with the hinge axis every retargeted clip
  bends that limb about (:data:`engine.motion.retarget_frames.CANON_HINGE`). Measured on
  the 9 validation files (every 4th frame), the real knees and elbows never go below
  -0.6 deg (the retargeted limbs are hinges).
* **Hyperextension**: a flexion below ``-HYPEREXTENSION_DEG`` (the knee or elbow bent
  backwards past straight by more than people do).
* **Centre of mass**: segment masses of de Leva's (1996) adjusted table (male) at points
  on the skeleton (:data:`SEGMENTS`).
* **Feet down**: a foot whose ankle and toe joints are both within :data:`FOOT_DOWN_M`
  of their heights when the character stands flat (rest pose on the floor).
* **Balance margin** (both feet down only): signed distance, metres, from the centre of
  mass's ground projection to the edge of the support polygon, the convex hull of each
  planted foot's ankle, toe joint and toe tip (positive inside). The heel reaches a few
  centimetres behind the ankle joint, so the polygon is slightly smaller than a real one.
* **Trunk tilt**: angle between vertical and the line from the pelvis (root) to the head
  joint (``upperneck``, the top of the neck), degrees; 1.1 deg in the rest pose.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass

import numpy as np

from engine import skeleton as sk
from engine.kinematics import quat_np as QN
from engine.kinematics.fk import fk
from engine.motion.retarget_frames import CANON_HINGE

J = sk.JOINT_INDEX
#: (upper joint, middle joint, end joint) of each limb whose middle joint is a hinge.
HINGED = {
    f"{s}{mid}": (f"{s}{up}", f"{s}{mid}", f"{s}{end}")
    for s in "lr"
    for up, mid, end in (("hip", "knee", "ankle"), ("shoulder", "elbow", "wrist"))
}
#: A knee or elbow bent backwards by more than this (degrees) is a joint-limit violation.
HYPEREXTENSION_DEG = 10.0
#: A foot is down when its ankle and toe joints are within this of their standing heights, metres.
FOOT_DOWN_M = 0.05
#: Segment -> (mass fraction, proximal joint, distal joint, where between them): de Leva (1996),
#: male. The head's point is half a neck beyond the head joint, the hand's 0.3 forearms
#: beyond the wrist; the trunk is the length-weighted mean of its bones' midpoints (:data:`TRUNK_BONES`).
SEGMENTS: dict[str, tuple[float, str, str, float]] = {
    "head": (0.0694, "lowerneck", "upperneck", 1.5),
    **{f"{s}upperarm": (0.0271, f"{s}shoulder", f"{s}elbow", 0.5) for s in "lr"},
    **{f"{s}forearm": (0.0162, f"{s}elbow", f"{s}wrist", 0.5) for s in "lr"},
    **{f"{s}hand": (0.0061, f"{s}elbow", f"{s}wrist", 1.3) for s in "lr"},
    **{f"{s}thigh": (0.1416, f"{s}hip", f"{s}knee", 0.5) for s in "lr"},
    **{f"{s}shank": (0.0433, f"{s}knee", f"{s}ankle", 0.5) for s in "lr"},
    **{f"{s}foot": (0.0137, f"{s}ankle", f"{s}toe", 0.5) for s in "lr"},
}
TRUNK_FRACTION = 1.0 - sum(s[0] for s in SEGMENTS.values())  # 0.4346
#: Bones of the trunk (pelvis, spine, shoulder girdle) as (parent, child) joint names.
TRUNK_BONES = (
    ("root", "lhip"),
    ("root", "rhip"),
    ("root", "lowerback"),
    ("lowerback", "upperback"),
    ("upperback", "chest"),
    ("chest", "lowerneck"),
    ("chest", "lclavicle"),
    ("lclavicle", "lshoulder"),
    ("chest", "rclavicle"),
    ("rclavicle", "rshoulder"),
)


@dataclass
class PoseCheck:
    """The measures of one pose (see the module doc).

    Attributes
    ----------
    flexion_deg : dict joint -> float
        Knees and elbows, degrees.
    violations : list of str
        E.g. ``"lknee hyperextended 23 deg"``.
    com : list of 3 floats
        Centre of mass, metres.
    feet_down : dict side -> bool
    balance_margin_cm : float or None
        None unless both feet are down.
    trunk_tilt_deg : float
    """

    flexion_deg: dict[str, float]
    violations: list[str]
    com: list[float]
    feet_down: dict[str, bool]
    balance_margin_cm: float | None
    trunk_tilt_deg: float

    @property
    def balanced(self) -> bool | None:
        """Centre of mass over the support polygon (None: not both feet down)."""
        return None if self.balance_margin_cm is None else self.balance_margin_cm >= 0.0

    def to_dict(self) -> dict:
        return asdict(self)


def flexion_deg(local_rot: np.ndarray, offsets: np.ndarray) -> dict[str, float]:
    """Signed flexion (degrees) of each knee and elbow of a pose ``local_rot (22, 4)``."""
    out = {}
    for mid, (up, _, end) in HINGED.items():
        a = offsets[J[mid]] / np.linalg.norm(offsets[J[mid]])  # upper bone, its own frame
        bend = np.cross(np.asarray(CANON_HINGE[up], float), a)
        bend /= np.linalg.norm(bend)
        d = QN.rotate(np.asarray(local_rot[J[mid]], float), offsets[J[end]])
        out[mid] = float(np.degrees(np.arctan2(d @ bend, d @ a)))
    return out


def hyperextensions(flexion: dict[str, float], limit: float = HYPEREXTENSION_DEG) -> list[str]:
    """The knees and elbows of ``flexion`` (degrees) bent backwards by more than ``limit``."""
    return [f"{j} hyperextended {-f:.0f} deg" for j, f in flexion.items() if f < -limit]


def centre_of_mass(positions: np.ndarray) -> np.ndarray:
    """Centre of mass ``(3,)`` of world joint positions ``(22, 3)``, metres."""
    p = np.asarray(positions, float)
    com = np.zeros(3)
    for frac, a, b, t in SEGMENTS.values():
        com += frac * (p[J[a]] + t * (p[J[b]] - p[J[a]]))
    lengths = np.array([np.linalg.norm(p[J[b]] - p[J[a]]) for a, b in TRUNK_BONES])
    mids = np.array([(p[J[a]] + p[J[b]]) / 2.0 for a, b in TRUNK_BONES])
    return com + TRUNK_FRACTION * (lengths @ mids) / lengths.sum()


def standing_heights(offsets: np.ndarray) -> np.ndarray:
    """Height of every joint ``(22,)`` above the floor when the skeleton stands in its
    rest pose on the floor (the lowest point is a toe tip), metres."""
    skel = sk.Skeleton(np.asarray(offsets, float))
    rest = skel.rest_positions()
    tip = rest[J["ltoe"], 2] + sk.END_SITES["ltoe"][2] * skel.scale
    return rest[:, 2] - min(rest[:, 2].min(), tip)


def feet_down(positions: np.ndarray, offsets: np.ndarray, tolerance: float = FOOT_DOWN_M) -> dict[str, bool]:
    """Per foot: ankle and toe joints within ``tolerance`` metres of their standing heights."""
    flat = standing_heights(offsets)
    return {
        side: bool(all(abs(positions[J[j], 2] - flat[J[j]]) <= tolerance for j in joints))
        for side, joints in sk.FEET.items()
    }


def convex_hull(points: np.ndarray) -> np.ndarray:
    """Counter-clockwise convex hull ``(K, 2)`` of ``points (N, 2)`` (Andrew's monotone chain)."""
    pts = sorted({(float(x), float(y)) for x, y in np.asarray(points, float)})
    if len(pts) < 3:
        return np.array(pts)

    def half(seq):
        out: list = []
        for p in seq:
            while len(out) >= 2 and _cross(out[-2], out[-1], p) <= 0:
                out.pop()
            out.append(p)
        return out[:-1]

    return np.array(half(pts) + half(pts[::-1]))


def _cross(o, a, b) -> float:
    return (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0])


def polygon_margin(point: np.ndarray, hull: np.ndarray) -> float:
    """Signed distance (metres) from ``point (2,)`` to the edge of the convex ``hull (K, 2)``
    (counter-clockwise): positive inside, negative outside; a hull of fewer than three
    points has no inside."""
    p = np.asarray(point, float)
    edges = [(hull[i], hull[(i + 1) % len(hull)]) for i in range(len(hull))] if len(hull) > 1 else []
    if not edges:
        return -float(np.linalg.norm(p - hull[0]))
    dist = min(_segment_distance(p, a, b) for a, b in edges)
    inside = len(hull) >= 3 and all(_cross(a, b, p) >= 0 for a, b in edges)
    return dist if inside else -dist


def _segment_distance(p: np.ndarray, a: np.ndarray, b: np.ndarray) -> float:
    ab = b - a
    t = 0.0 if not ab @ ab > 0 else float(np.clip((p - a) @ ab / (ab @ ab), 0.0, 1.0))
    return float(np.linalg.norm(p - (a + t * ab)))


def support_polygon(positions: np.ndarray, rotations: np.ndarray, offsets: np.ndarray, sides) -> np.ndarray:
    """Convex hull ``(K, 2)`` of the ankle, toe joint and toe tip of the feet ``sides``."""
    scale = sk.Skeleton(np.asarray(offsets, float)).scale
    pts = []
    for side in sides:
        ankle, toe = sk.FEET[side]
        tip = positions[J[toe]] + QN.rotate(rotations[J[toe]], sk.END_SITES[toe] * scale)
        pts += [positions[J[ankle], :2], positions[J[toe], :2], tip[:2]]
    return convex_hull(np.array(pts))


def trunk_tilt_deg(positions: np.ndarray) -> float:
    """Angle (degrees) between vertical and the pelvis-to-head-joint line of ``positions (22, 3)``."""
    v = positions[J["upperneck"]] - positions[J["root"]]
    return float(np.degrees(np.arccos(np.clip(v[2] / np.linalg.norm(v), -1.0, 1.0))))


def check_pose(local_rot: np.ndarray, root_pos: np.ndarray, offsets: np.ndarray) -> PoseCheck:
    """Every measure of the module doc for one pose."""
    offsets = np.asarray(offsets, float)
    positions, rotations = fk(np.asarray(local_rot, float), np.asarray(root_pos, float), offsets)
    flex = flexion_deg(local_rot, offsets)
    com = centre_of_mass(positions)
    down = feet_down(positions, offsets)
    margin = None
    if all(down.values()):
        margin = 100.0 * polygon_margin(com[:2], support_polygon(positions, rotations, offsets, sk.FEET))
    return PoseCheck(flex, hyperextensions(flex), [float(x) for x in com], down, margin, trunk_tilt_deg(positions))
