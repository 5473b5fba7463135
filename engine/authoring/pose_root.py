"""Where pose mode holds the pelvis during a solve (:class:`engine.authoring.pose_mode.PoseMode`),
and how a low reach splits between the trunk and the legs.

A target on the root puts the pelvis there; else it crouches towards a wrist target
below what the arm reaches from a trunk bent forward by ``PoseOptions.stoop_deg``
(``PoseOptions.crouch_share``, :func:`crouch_from`, :func:`arm_low_points`) and takes a
balance step that keeps the centre of mass over the planted feet
(``PoseOptions.balance``, :func:`balance_step`), cut short where it would take a reaching
arm's shoulder from its hand while the centre of mass stays well inside the feet
(:func:`reach_share`). :func:`root_where` is that rule. A
wrist target above that low point is the trunk's: :func:`stoop_targets` pulls the
shoulder towards it in the latent solve, so a person's reach to a knee stoops with the
legs nearly straight and a reach to the floor crouches. :data:`FOOT_OF` and
:func:`moved_feet` say which feet a target moves.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import NamedTuple

import numpy as np

from engine import skeleton as sk
from engine.authoring.character import Pose
from engine.authoring.pose_metrics import centre_of_mass, convex_hull, polygon_margin, trunk_tilt_deg
from engine.authoring.pose_options import LOWEST_ROOT, SQUAT_FROM, STOOP_REACH, PoseOptions
from engine.authoring.targets import JointTarget
from engine.solver.limb_ik import LIMBS

#: The foot (``"l"``, ``"r"``) of each foot joint.
FOOT_OF = {"lankle": "l", "ltoe": "l", "rankle": "r", "rtoe": "r"}


def moved_feet(targets: Mapping[str, JointTarget]) -> set[str]:
    """The feet (``"l"``, ``"r"``) that an active target of ``targets`` moves."""
    return {FOOT_OF[t.joint] for t in targets.values() if t.joint in FOOT_OF and t.active}


def arm_length(positions: np.ndarray, wrist: int) -> float:
    """Length (metres) of the arm that ``wrist`` ends in ``positions (22, 3)``: its two bones."""
    a, b = LIMBS[wrist]
    return float(np.linalg.norm(positions[b] - positions[a]) + np.linalg.norm(positions[wrist] - positions[b]))


def stooped_shoulder_heights(positions: np.ndarray, stoop_deg: float) -> dict[int, float]:
    """Per wrist, the height (metres) of its shoulder in the pose with joint
    ``positions (22, 3)`` metres, with the trunk turned forward by
    ``stoop_deg`` degrees about the hip line (Rodrigues' rotation of the shoulder about
    the axis from the right hip to the left: positive turns the top forward)."""
    p = np.asarray(positions, float)
    hips = 0.5 * (p[sk.JOINT_INDEX["lhip"]] + p[sk.JOINT_INDEX["rhip"]])
    axis = p[sk.JOINT_INDEX["lhip"]] - p[sk.JOINT_INDEX["rhip"]]
    axis[2] = 0.0
    axis /= max(float(np.linalg.norm(axis)), 1e-12)
    c, s = np.cos(np.radians(stoop_deg)), np.sin(np.radians(stoop_deg))
    out = {}
    for w, (a, _) in LIMBS.items():
        if sk.JOINT_NAMES[w] not in FOOT_OF:
            v = p[a] - hips
            out[w] = float(hips[2] + (v[2] * c + np.cross(axis, v)[2] * s))  # the axis is level: no (1 - c) term
    return out


def arm_low_points(positions: np.ndarray, stoop_deg: float = 0.0) -> dict[int, float]:
    """Per wrist, the lowest height (metres) it reaches from its shoulder in the pose
    with joint ``positions (22, 3)`` metres with the trunk bent forward by ``stoop_deg``
    degrees at the hips (:func:`stooped_shoulder_heights`), the arm hanging straight
    down from there."""
    p = np.asarray(positions, float)
    return {w: h - arm_length(p, w) for w, h in stooped_shoulder_heights(p, stoop_deg).items()}


def crouch_from(joint: int, low_points: Mapping[int, float], options: PoseOptions) -> float:
    """Height (metres) below which a dragged ``joint``'s target lowers the pelvis: a
    wrist's low point (``low_points``, :func:`arm_low_points` of the starting pose with
    the trunk bent by ``options.stoop_deg``) when ``options.crouch_below_reach`` (a
    target the stooping body reaches bends no knee), else no limit."""
    if options.crouch_below_reach and joint in low_points:
        return low_points[joint]
    return np.inf


def reaching(targets: Mapping[str, JointTarget]) -> list[JointTarget]:
    """The active targets of ``targets`` that may crouch the pelvis: neither the root's
    nor a foot joint's."""
    return [t for t in targets.values() if t.active and t.joint != "root" and t.joint not in FOOT_OF]


def reach_crouches(targets: Mapping[str, JointTarget], low_points: Mapping[int, float], options: PoseOptions) -> bool:
    """Whether a :func:`reaching` target of ``targets`` lies below where it lowers the pelvis
    (:func:`crouch_from`), so that a solve without a target on the root crouches for it."""
    if options.crouch_share <= 0:
        return False
    return any(t.position[2] < crouch_from(t.index, low_points, options) for t in reaching(targets))


def stoop_targets(stance: "Stance", where: np.ndarray, low_points: Mapping[int, float]) -> list[JointTarget]:
    """Targets on the shoulders that bend the trunk to the wrist targets a stoop reaches
    (``PoseOptions.stoop_deg``), for a solve from ``stance.pose`` with the root at
    ``where (3,)`` metres: for each :func:`reaching` wrist target at or above its low
    point (``low_points``, :func:`arm_low_points` with the stoop) that lies more than
    :data:`STOOP_REACH` of the arm's length from its shoulder, a target on that shoulder
    at that distance from the wrist target, on the line to where the shoulder is, with the
    wrist target's weight. A reach below the low point crouches instead (:func:`root_where`).
    Under a pelvis-only target (the pelvis dragged alone) nothing crouches for a reach,
    and the shoulder is pulled towards every wrist target beyond that distance, low or
    not: the trunk leans to a hand the lowered pelvis took out of the carried arm's
    reach. None under another active target on the root (a squat, the hips held up): the
    latent bends the body to the reach from there as it finds, and a pull there moved
    the knees under a hand being dragged onto them and lowered hips held at standing
    height."""
    pose, targets, _, o = stance
    root = targets.get("root")
    held = root is not None and root.active
    if o.stoop_deg <= 0 or (root is not None and root.active and not root.pelvis_only):
        return []
    p, out = pose.positions, []
    for t in reaching(targets):
        if t.index not in low_points or (not held and t.position[2] < low_points[t.index]):
            continue
        shoulder = LIMBS[t.index][0]
        reach = STOOP_REACH * arm_length(p, t.index)
        away = p[shoulder] - p[0] + np.asarray(where, float) - t.position
        dist = float(np.linalg.norm(away))
        if dist > reach:
            out.append(JointTarget(sk.JOINT_NAMES[shoulder], t.position + away * (reach / dist), weight=t.weight))
    return out


class Stance(NamedTuple):
    """What the pelvis rule reads of a pose-mode state: the current ``pose``, the user's
    ``targets`` by joint name, the ``planted`` foot joints' positions (3,) metres and the
    ``options``."""

    pose: Pose
    targets: Mapping[str, JointTarget]
    planted: Mapping[str, np.ndarray]
    options: PoseOptions


def shortfall(stance: Stance) -> float:
    """Largest distance (metres) of a targeted wrist or ankle from its target in
    ``stance.pose`` (after the exact limb step, how far the target lies beyond the limb's
    reach), and while the pelvis has a target (a crouch), of the pelvis from its height and
    of a planted foot joint from its place: a fast drag sends few events, and one round
    left a squat high with the feet rolled onto the heels. 0 without such targets."""
    pose, targets, planted, options = stance
    gaps = [
        np.linalg.norm(pose.positions[t.index] - t.position) for t in targets.values() if t.active and t.index in LIMBS
    ]
    root = targets.get("root")
    if root is not None and root.active:
        gaps.append(abs(pose.root_pos[2] - root.position[2]))
        if options.plant_feet:
            moved = moved_feet(targets)
            gaps += [
                np.linalg.norm(pose.positions[sk.JOINT_INDEX[j]] - p)
                for j, p in planted.items()
                if FOOT_OF[j] not in moved
            ]
    return float(max(gaps, default=0.0))


#: A trunk leaning further than this (degrees) from vertical stoops: its balance step
#: keeps the centre of mass within ``PoseOptions.crouch_tolerance`` of the middle of the
#: feet, as a person stooping puts the hips back. An arm's reach with the trunk upright
#: (a 30-cm reach forward leans it about 20 degrees) keeps ``balance_tolerance``.
STOOP_TILT = 30.0

#: How far the toe tip lies beyond the toe joint, as a share of the foot from the ankle to
#: the toe joint (the toe's end site against its bone, both along the foot).
TOE_SHARE = float(
    np.linalg.norm(sk.END_SITES["ltoe"]) / np.linalg.norm(sk.Skeleton.canonical().offsets[sk.JOINT_INDEX["ltoe"]])
)


def support_middle(planted: Mapping[str, np.ndarray]) -> np.ndarray:
    """The level middle (2,) metres of the planted feet's support: per foot, halfway
    from its ankle to its toe tip (the toe tip :data:`TOE_SHARE` of the foot beyond the
    toe joint; a foot planted by one joint alone counts that joint), averaged over the
    feet. The benchmark's support polygon spans the same ankle-to-tip stretch of each
    foot. Standing poses of the shipped validation files keep their centre of mass over
    this middle (median 0.4 cm ahead of it, quartiles 2.4 cm behind and 2.9 cm ahead;
    the neutral pose 3.5 cm ahead); the mean of the ankle and toe joints, which leaves
    the toes ahead of the toe joint out, lies 6.5 cm behind it, so that every standing
    pose would lean on the balance tolerance."""
    feet = []
    for side in ("l", "r"):
        ankle, toe = planted.get(f"{side}ankle"), planted.get(f"{side}toe")
        if ankle is not None and toe is not None:
            feet.append(ankle[:2] + 0.5 * (1.0 + TOE_SHARE) * (toe[:2] - ankle[:2]))
        elif ankle is not None or toe is not None:
            feet.append(np.asarray(ankle if ankle is not None else toe, float)[:2])
    return np.mean(feet, axis=0)


def balance_step(stance: Stance, tolerance: float, crouch: bool = False) -> np.ndarray:
    """The level move (2,) metres of the pelvis that one solve makes towards balance
    (see ``PoseOptions.balance``): none while a foot is dragged or the centre of mass
    lies within ``tolerance`` metres of the middle of the planted feet's support
    (:func:`support_middle`; a trunk leaning more than :data:`STOOP_TILT` balances
    within the tighter of ``tolerance`` and ``crouch_tolerance``). A ``crouch`` (a pelvis
    lowered by its target, ``PoseOptions.crouch_balance``) balances over the mean of the
    planted joints instead, 6.5 cm behind that middle: the squat's figures are measured
    against it (docs/authoring.md, *A squat on the whole foot*), and balanced over the
    support's middle the squat's trunk leans 3 degrees further (14) and its pelvis ends
    0.2 cm further from its height, for a balance margin 1.3 cm larger."""
    pose, targets, planted, o = stance
    if not (o.balance and o.plant_feet) or moved_feet(targets) or not planted:
        return np.zeros(2)
    if crouch:
        middle = np.mean([p[:2] for p in planted.values()], axis=0)
    else:
        middle = support_middle(planted)
        if trunk_tilt_deg(pose.positions) > STOOP_TILT:
            tolerance = min(tolerance, o.crouch_tolerance)
    off = middle - centre_of_mass(pose.positions)[:2]
    dist = float(np.linalg.norm(off))
    if dist <= tolerance:
        return np.zeros(2)
    return o.balance_gain * off * (1.0 - tolerance / dist)


#: How far (metres) inside the planted feet's support a standing body's centre of mass
#: stays while the balance step is cut short for a reaching arm (:func:`reach_share`).
REACH_MARGIN = 0.06
#: Shares of a balance step tried, largest first, by :func:`within_arms`.
STEP_SHARES = np.linspace(1.0, 0.0, 11)


def within_arms(stance: Stance, step: np.ndarray, low_points: Mapping[int, float]) -> float:
    """The largest share of the level pelvis move ``step (2,)`` metres (of
    :data:`STEP_SHARES`) that takes no shoulder of a targeted wrist further than
    :data:`STOOP_REACH` of its arm's length from that target, or further than it is
    already: a hand the user pinned holds the body (a crouch holding a rail), and the
    balance must not pull it off. Only wrist targets at or above their low point
    (``low_points``, :func:`arm_low_points` with the stoop) count: a reach below it (a
    hand to the shin) is the crouch's, which balances as it goes."""
    pose, targets = stance.pose, stance.targets
    p = pose.positions
    wrists = [t for t in reaching(targets) if t.index in low_points and t.position[2] >= low_points[t.index]]
    if not wrists or not np.any(step):
        return 1.0
    move = np.array([step[0], step[1], 0.0])
    shoulders = np.array([p[LIMBS[t.index][0]] for t in wrists])
    goals = np.array([t.position for t in wrists])
    limit = np.maximum(
        [STOOP_REACH * arm_length(p, t.index) for t in wrists], np.linalg.norm(shoulders - goals, axis=1)
    )
    for share in STEP_SHARES:
        if np.all(np.linalg.norm(shoulders + share * move - goals, axis=1) <= limit):
            return float(share)
    return 0.0


def root_where(
    stance: Stance, standing_root: float, low_points: Mapping[int, float], adjust: bool = True
) -> np.ndarray:
    """Where the root is held during a solve from ``stance.pose`` (3,) metres.

    A target on the root puts it there (while crouching, only at its height: the pelvis
    keeps its level place and, with ``adjust``, takes the crouch's balance step from
    it); else, with ``adjust``, the crouch and balance steps move it (see
    :class:`PoseOptions`), which a solve without latent steps does not do, so that it
    only puts the limbs on their targets. ``standing_root`` is the pelvis's standing
    height, metres; ``low_points`` the wrists' (:func:`crouch_from`).
    """
    pose, targets, _, o = stance
    root = targets.get("root")
    if root is not None and root.active:
        where = np.asarray(root.position, float).copy()
        if o.crouch_balance and where[2] < standing_root - SQUAT_FROM:
            # a crouching pelvis keeps its own level place, balanced from there
            step = balance_step(stance, o.crouch_tolerance, crouch=True) if adjust else np.zeros(2)
            where[:2] = pose.root_pos[:2] + step * within_arms(stance, step, low_points)
        return where
    where = pose.root_pos.copy()
    if not adjust:
        return where
    user = reaching(targets)
    if o.crouch_share > 0 and user:
        # the part of the way from the joint down to its target that lies below where it crouches from
        low = {t.index: crouch_from(t.index, low_points, o) for t in user}
        drop = min(
            0.0,
            min(min(t.position[2], low[t.index]) - min(pose.positions[t.index, 2], low[t.index]) for t in user),
        )
        where[2] = float(np.clip(where[2] + o.crouch_share * drop, LOWEST_ROOT * standing_root, standing_root))
    step = balance_step(stance, o.balance_tolerance)
    where[:2] += step * reach_share(stance, step, low_points)
    return where


def support_hull(planted: Mapping[str, np.ndarray]) -> np.ndarray:
    """The planted feet's support polygon ``(K, 2)`` metres: the convex hull of each foot's
    ankle, toe joint and toe tip (:data:`TOE_SHARE` of the foot beyond the toe joint), as
    the benchmark's support polygon spans them."""
    pts = []
    for side in ("l", "r"):
        ankle, toe = planted.get(f"{side}ankle"), planted.get(f"{side}toe")
        if ankle is not None and toe is not None:
            pts += [ankle[:2], toe[:2], (toe + TOE_SHARE * (toe - ankle))[:2]]
        elif ankle is not None or toe is not None:
            pts.append(np.asarray(ankle if ankle is not None else toe, float)[:2])
    return convex_hull(np.array(pts))


def reach_share(stance: Stance, step: np.ndarray, low_points: Mapping[int, float]) -> float:
    """The share of a standing body's balance step ``step (2,)`` metres that it takes: all
    of it, or, where it would take the shoulder of a targeted wrist out of that arm's
    reach of its target (:func:`within_arms`), as much as :func:`within_arms` allows
    while the centre of mass, moved with the pelvis, stays :data:`REACH_MARGIN` inside
    the planted feet's support (:func:`support_hull`), else the least share that keeps
    it there (all of it when none does)."""
    share = within_arms(stance, step, low_points)
    # taken whole, the step leaves a reach 50 cm out 8.0 cm from its goal (50 cm forward
    # 6.3), the pelvis 13-14 cm back and the centre of mass 8 cm inside the feet
    if share >= 1.0:
        return 1.0
    hull = support_hull(stance.planted)
    com = centre_of_mass(stance.pose.positions)[:2]
    for s in STEP_SHARES[::-1]:
        if s >= share and polygon_margin(com + s * step, hull) >= REACH_MARGIN:
            return float(s)
    return 1.0
