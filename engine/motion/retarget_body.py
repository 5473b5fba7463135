"""Body-defined bone frames: the twist of limbs, hands, feet and head read off the body.

A canonical joint's world rotation is ``G(t) = B(t) B0^-1``: ``B(t)`` is a frame built,
frame by frame, from the positions of the body (its x axis along the bone, its y axis
from a reference the body defines) and ``B0`` the same frame on the canonical rest pose
(T-pose). Nothing of the source rig's joint axes enters, so its rest conventions (T- or
A-pose, bone axes along +X or +Y, twist joints, a twist that a child undoes) cannot
show in the canonical rotations. The rules (``docs/skeleton.md``, *Body-defined twist*):

* **thigh and shin, upper arm and forearm**: the bone, and the normal of the limb's
  bending plane (hip-knee-ankle, shoulder-elbow-wrist); a straight limb's plane is
  undefined, so a second reference takes over as the limb straightens (:data:`STRAIGHT`):
  the foot's direction for the legs (a knee bends towards the toes), the source's own
  twist for the arms;
* **wrist**: the hand's direction (wrist to the knuckles' midpoint) and the thumb side
  (little-finger to index knuckle); the knuckles must be children of the wrist joint,
  so that they move rigidly with the hand;
* **ankle**: the foot's direction (to the toe, or the toe tip) and the sole's normal,
  taken as the shin's direction off the foot (no rig here carries a landmark across the
  sole); **toe**: the toe's direction (to its tip) and the same shin reference (with the
  strategy's ``sole_toe_tips`` the canonical rest's tip lies on the sole's line,
  :func:`sole_tip`, where source rigs put theirs);
* **lower neck and head**: the head's direction and the face's eye line.

Where the rig lacks the defining points, a documented rule (:data:`RULES`) puts them on
the body (:func:`engine.motion.retarget_rotations.rule_points`): a hand without knuckles
that are its children but with an index (finger base) and a thumb takes its direction
towards the index and its thumb side from the thumb's tip, both rigid with the hand; a
head without eyes gets eyes where the canonical ones sit in the head's own frame. A joint
that neither the body nor a rule defines keeps the source's rotation with one constant
alignment (:mod:`engine.motion.retarget_frames`).
"""

from __future__ import annotations

import numpy as np

from engine import skeleton as sk
from engine.kinematics import quaternion as Q
from engine.motion.retarget_frames import CANON_HINGE, CANON_LANDMARKS, frame

#: Weight of the straight-limb reference against the bending plane's normal (whose
#: length is the sine of the bend) when the limb is straight; it fades to 0 at
#: :data:`FADE_DEG` of bend, so a bent limb's twist is its bending plane's alone.
STRAIGHT = 0.2
FADE_DEG = 30.0
#: Angle (degrees) about the hand's direction from the thumb side (the knuckle line) to
#: the thumb's tip, towards the palm: a hand frame built on the thumb is turned back by it.
#: Measured on the shared takes on both rigs: the CMU rig's thumb rule against the
#: knuckle lines of the iClone and Daz copies (docs/skeleton.md).
THUMB_PALM_DEG = 75.0
#: Canonical joints whose rotation the body rules define.
BODY_JOINTS = tuple(f"{s}{j}" for s in "lr" for j in ("hip", "knee", "ankle", "toe", "shoulder", "elbow", "wrist")) + (
    "lowerneck",
    "upperneck",
)
#: The documented rules for rigs without the defining points: (rule name, the points
#: that stand in (:func:`engine.motion.retarget_rotations.rule_points`), the joints they define).
RULES = (
    ("thumb", ("l_hand_tip", "l_thumb_tip"), ("lwrist",)),
    ("thumb", ("r_hand_tip", "r_thumb_tip"), ("rwrist",)),
    ("head frame", ("l_eye", "r_eye"), ("lowerneck", "upperneck")),
)
#: A wrist with neither knuckles nor a finger base and thumb ("no twist",
#: :func:`engine.motion.retarget_rotations.world_rotations`) keeps the swing of the
#: source's hand relative to the forearm and no twist about the hand's direction.


def _unit(v: np.ndarray) -> np.ndarray:
    return v / np.maximum(np.linalg.norm(v, axis=-1, keepdims=True), 1e-9)


def _first(pts: dict, names) -> str | None:
    return next((n for n in names if n in pts), None)


def _limb_reference(pts, a, b, c, straight: np.ndarray | None) -> np.ndarray | None:
    """Bending-plane normal of the limb ``a-b-c`` (length: sine of the bend), plus the unit
    straight-limb reference ``straight`` (F, 3) with a weight that is :data:`STRAIGHT` for
    a straight limb and fades to 0 at a bend of :data:`FADE_DEG`."""
    if not all(k in pts for k in (a, b, c)) or straight is None:
        return None
    n = np.cross(_unit(pts[b] - pts[a]), _unit(pts[c] - pts[b]))
    sine = np.linalg.norm(n, axis=-1, keepdims=True)
    weight = STRAIGHT * np.clip(1.0 - sine / np.sin(np.radians(FADE_DEG)), 0.0, 1.0) ** 2
    return n + weight * _unit(straight)


def _hand(pts, s: str):
    """The wrist's (direction, thumb-side) pair of ``(F, 3)`` vectors, or None: towards
    the knuckles' midpoint, and from the little finger's knuckle to the index's; without
    those, towards the index (finger base) and towards the thumb's tip (the ``thumb`` rule)."""
    w, index, pinky = f"{s}wrist", f"{s}_index", f"{s}_pinky"
    if all(k in pts for k in (w, index, pinky)):
        return pts[f"{s}_hand_mid"] - pts[w], pts[index] - pts[pinky]
    if all(k in pts for k in (w, f"{s}_hand_tip", f"{s}_thumb_tip")):
        return pts[f"{s}_hand_tip"] - pts[w], pts[f"{s}_thumb_tip"] - pts[w]
    return None


def _thumb_to_knuckles(b: np.ndarray, s: str) -> np.ndarray:
    """A hand frame ``(F, 4)`` built on the thumb's tip turned back to the knuckle line's:
    the tip sits :data:`THUMB_PALM_DEG` from the thumb side towards the palm (frame +z on
    the left hand, -z on the right)."""
    turn = np.radians(THUMB_PALM_DEG if s == "l" else -THUMB_PALM_DEG)
    r = Q.from_axis_angle(np.array([1.0, 0.0, 0.0]), np.array(-turn))
    return Q.mul(b, np.broadcast_to(r, b.shape))


def rule_joints(points: dict) -> dict[str, str]:
    """Joint -> the :data:`RULES` name whose stand-in points are all in ``points``."""
    return {j: name for name, need, joints in RULES if all(k in points for k in need) for j in joints}


def body_frames(
    pts: dict[str, np.ndarray], arm_straight: dict[str, np.ndarray] | None = None, canonical: bool = False
) -> dict[str, np.ndarray]:
    """World bone frames ``(F, 4)`` of the :data:`BODY_JOINTS` the points define.

    Parameters
    ----------
    pts : dict
        Canonical-named world points ``(F, 3)``, metres, canonical axes: joints and
        landmarks (with :func:`engine.motion.retarget_frames.add_derived`'s midpoints).
    arm_straight : dict, optional
        Per arm joint, the world reference ``(F, 3)`` used while the arm is straight
        (the y axis of the source's own, constantly aligned frame).
    canonical : bool
        The canonical rest pose: limbs are straight, their references are
        :data:`engine.motion.retarget_frames.CANON_HINGE`.
    """
    out: dict[str, np.ndarray] = {}
    arm_straight = arm_straight or {}
    for s in "lr":
        hip, knee, ankle, toe = (f"{s}{j}" for j in ("hip", "knee", "ankle", "toe"))
        foot_end = _first(pts, (toe, f"{s}_toe_tip"))
        for a, b, c, straight in (
            (
                hip,
                knee,
                ankle,
                None
                if foot_end is None or ankle not in pts
                else np.cross(pts[foot_end] - pts[ankle], pts[knee] - pts[hip])
                if hip in pts and knee in pts
                else None,
            ),
            (f"{s}shoulder", f"{s}elbow", f"{s}wrist", arm_straight.get(f"{s}shoulder")),
        ):
            if canonical:
                for j, child in ((a, b), (b, c)):
                    if j in pts and child in pts:
                        out[j] = frame(pts[child] - pts[j], np.broadcast_to(CANON_HINGE[j], pts[j].shape))[0]
                continue
            ref = _limb_reference(pts, a, b, c, straight)
            if ref is not None:
                out[a] = frame(pts[b] - pts[a], ref)[0]
                out[b] = frame(pts[c] - pts[b], ref)[0]
        if ankle in pts and knee in pts and foot_end is not None:
            shin = pts[knee] - pts[ankle]
            out[ankle] = frame(pts[foot_end] - pts[ankle], shin)[0]
            if toe in pts and f"{s}_toe_tip" in pts:
                out[toe] = frame(pts[f"{s}_toe_tip"] - pts[toe], shin)[0]
        hand = _hand(pts, s)
        if hand is not None:
            out[f"{s}wrist"] = frame(*hand)[0]
            if f"{s}_pinky" not in pts:
                out[f"{s}wrist"] = _thumb_to_knuckles(out[f"{s}wrist"], s)
    if all(k in pts for k in ("l_eye", "r_eye", "upperneck", "lowerneck")):
        eyes = pts["l_eye"] - pts["r_eye"]
        out["lowerneck"] = frame(pts["upperneck"] - pts["lowerneck"], eyes)[0]
        out["upperneck"] = frame(eyes, pts["eyes_mid"] - pts["upperneck"])[0]
    return out


def sole_tip(side: str) -> np.ndarray:
    """Offset (3,) of a toe tip on the sole's line from the canonical toe joint, metres: as
    long as the toe's end site and with its heading, horizontal in the T-pose. Source rigs put their
    toe-tip landmark there (iClone's middle-toe joint, the CMU rig's end site) rather than
    where the canonical end site points, on the floor 25 degrees below it."""
    end = sk.END_SITES[f"{side}toe"]
    flat = np.array([end[0], end[1], 0.0])
    return flat / np.linalg.norm(flat) * float(np.linalg.norm(end))


def canonical_body_frames(offsets: np.ndarray = sk.REST_OFFSETS, sole: bool = False) -> dict[str, np.ndarray]:
    """:func:`body_frames` ``(4,)`` of the canonical rest pose (T-pose); with ``sole`` the
    toe tips are :func:`sole_tip` instead of the toes' end sites."""
    from engine.motion.retarget_frames import add_derived

    rest = sk.Skeleton(offsets=np.asarray(offsets, float)).rest_positions()
    pts = {n: rest[i][None] for i, n in enumerate(sk.JOINT_NAMES)}
    for lm, (anchor, off) in CANON_LANDMARKS.items():
        if sole and lm.endswith("toe_tip"):
            off = sole_tip(lm[0])
        pts[lm] = (rest[sk.JOINT_INDEX[anchor]] + off)[None]
    add_derived(pts)
    return {j: q[0] for j, q in body_frames(pts, canonical=True).items()}


def body_rotations(
    pts: dict[str, np.ndarray], arm_straight: dict[str, np.ndarray] | None = None, sole_toe_tips: bool = False
) -> dict[str, np.ndarray]:
    """Canonical world rotations ``G = B(t) B0^-1`` ``(F, 4)`` of the joints the body defines.

    With ``sole_toe_tips`` (a :class:`~engine.motion.retarget_strategy.RetargetStrategy`
    choice) the rest frames ``B0`` take the toe tips on the sole's line (:func:`sole_tip`)."""
    canon = canonical_body_frames(sole=sole_toe_tips)
    return {
        j: Q.mul(b, np.broadcast_to(Q.conjugate(canon[j]), b.shape)) for j, b in body_frames(pts, arm_straight).items()
    }
