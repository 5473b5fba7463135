"""Canonical world rotations of a source clip: body-defined where the body defines them.

:func:`world_rotations` gives every mapped joint one constant alignment ``R``
(``G_c = G_s R``, :mod:`engine.motion.retarget_frames`) and, with the strategy's
``body_twist``, replaces the rotation of the joints the body defines (:mod:`engine.motion.retarget_body`) by their
body-defined one; ``R`` is then the mean of ``G_s^-1 G_c`` over the clip, which writing
back onto the source rig uses (:mod:`engine.motion.write_back`).
"""

from __future__ import annotations

import numpy as np

from engine import skeleton as sk
from engine.kinematics import quaternion as Q
from engine.kinematics.fk import ancestors, children
from engine.motion import retarget_body as RB
from engine.motion import retarget_frames as RF
from engine.motion.bvh import RawBVH
from engine.motion.retarget_strategy import RetargetStrategy
from engine.motion.rigs import RigProfile

_CANON_FRAMES = RF.canonical_frames()
_BODY_FRAMES = RB.canonical_body_frames()


def rigid_hands(raw: RawBVH, prof: RigProfile) -> set[str]:
    """Sides (``"l"``, ``"r"``) whose index and little-finger knuckles are children of the
    wrist joint, so that they move rigidly with the hand (the wrist's body rule needs it)."""
    out = set()
    for s in ("l", "r"):
        wrist = prof.joints.get(f"{s}wrist")
        knuckles = [prof.landmarks.get(f"{s}_{f}", "") for f in ("index", "pinky")]
        if wrist and all(
            k in raw.names and raw.parents[raw.names.index(k)] == raw.names.index(wrist) for k in knuckles
        ):
            out.add(s)
    return out


def _chain_tip(raw: RawBVH, j: int, wpos: np.ndarray, wrot: np.ndarray, ends: dict, units: float) -> np.ndarray:
    """World point ``(F, 3)`` at the end of joint ``j``'s first-child chain (its end site
    when there is one)."""
    while kids := children(raw.parents, j):
        j = kids[0]
    tip = wpos[:, j]
    if j in ends:
        tip = tip + Q.rotate(wrot[:, j], np.broadcast_to(np.asarray(ends[j]) * units, tip.shape))
    return tip


def tip_points(
    raw: RawBVH, prof: RigProfile, wpos: np.ndarray, wrot: np.ndarray, ends: dict, hands: set[str]
) -> dict[str, np.ndarray]:
    """World points ``(F, 3)`` (canonical axes, metres) the rules for rigs without knuckles
    or eyes need: the thumb's tip ``{s}_thumb_tip`` on the sides whose knuckles are not
    rigid with the hand (not in ``hands``), and the head's top ``head_top``.

    The thumb is the landmark ``{s}_thumb`` or else the wrist's descendant nearest it whose
    name holds "thumb"; a tip is the end of the joint's first-child chain (the end site
    when there is one). ``wpos`` / ``wrot`` ``(F, J, 3/4)`` are the source's world positions
    and rotations, ``ends`` its end-site OFFSETs (source units) by joint index."""
    out = {}
    for s in ("l", "r"):
        wrist = prof.joints.get(f"{s}wrist")
        if s in hands or not wrist:
            continue
        w = raw.names.index(wrist)
        chains = {j: ancestors(raw.parents, j) for j in range(len(raw.names))}
        depth = {j: c.index(w) for j, c in chains.items() if w in c}  # the wrist's descendants
        below = set(depth)
        named = prof.landmarks.get(f"{s}_thumb")
        cands = (
            [raw.names.index(named)]
            if named in raw.names
            else sorted((j for j in below if "thumb" in raw.names[j].lower()), key=lambda j: depth[j])
        )
        if cands:
            out[f"{s}_thumb_tip"] = _chain_tip(raw, cands[0], wpos, wrot, ends, prof.units_to_m)
    head = prof.joints.get("upperneck")
    if head:
        out["head_top"] = _chain_tip(raw, raw.names.index(head), wpos, wrot, ends, prof.units_to_m)
    return out


def _rigid(point: np.ndarray, origin: np.ndarray, rot: np.ndarray) -> np.ndarray:
    """``point`` ``(F, 3)`` made rigid with the frame ``rot`` ``(F, 4)`` at ``origin``: its
    mean over the clip in that frame, put back in the world every frame (fingers that the
    rig animates about the hand then do not turn the hand's frame)."""
    local = Q.rotate(Q.conjugate(rot), point - origin).mean(0)
    return origin + Q.rotate(rot, np.broadcast_to(local, origin.shape))


def rule_points(pts: dict, aligned: dict, wrot, idx, prof: RigProfile, hands: set[str]) -> dict[str, np.ndarray]:
    """Points the documented rules put on the body where the rig lacks the defining ones.

    * A hand whose knuckles are not its children but which has an index (finger base)
      landmark and a thumb: the index joint (or, when it sits on the wrist, nothing) and
      the thumb's tip, each made rigid with the source's hand joint (:func:`_rigid`):
      ``{s}_hand_tip`` and ``{s}_thumb_tip``.
    * A head without eyes: eyes placed where the canonical ones sit on a head whose up
      direction is the source head's (towards its top: the end of its chain, or without one
      the canonical head top on the source head's axes) and which faces as
      the chest does (its left axis is the chest's, made square to the head's up): the
      head turns with the chest and nods and tilts with its bone, with no twist of its
      own. The source head joint's own twist is not used: on CMU takes converted to the
      MotionBuilder rig it is turned up to 165 degrees from the chest (docs/skeleton.md)."""
    out = {}
    for s in ("l", "r"):
        wrist = prof.joints.get(f"{s}wrist")
        if s in hands or not wrist or f"{s}_index" not in pts or f"{s}_thumb_tip" not in pts:
            continue
        rot, origin = wrot[:, idx[wrist]], pts[f"{s}wrist"]
        if np.median(np.linalg.norm(pts[f"{s}_index"] - origin, axis=-1)) < 0.01:
            continue  # an index joint on the wrist gives no direction
        out[f"{s}_hand_tip"] = _rigid(pts[f"{s}_index"], origin, rot)
        out[f"{s}_thumb_tip"] = _rigid(pts[f"{s}_thumb_tip"], origin, rot)
    torso = next((j for j in ("chest", "upperback", "lowerback", "root") if j in aligned), None)
    if "l_eye" not in pts and "r_eye" not in pts and "upperneck" in pts and torso:
        shape = pts["upperneck"].shape
        up = (
            pts["head_top"] - pts["upperneck"]
            if "head_top" in pts
            else (Q.rotate(aligned["upperneck"], np.broadcast_to(sk.END_SITES["upperneck"], shape)))
        )
        left = Q.rotate(aligned[torso], np.broadcast_to([1.0, 0.0, 0.0], shape))
        rest, _ = RF.frame(sk.END_SITES["upperneck"], np.array([1.0, 0.0, 0.0]))
        head = Q.mul(RF.frame(up, left)[0], np.broadcast_to(Q.conjugate(rest), shape[:-1] + (4,)))
        for lm in ("l_eye", "r_eye"):
            out[lm] = pts["upperneck"] + Q.rotate(head, np.broadcast_to(RF.CANON_LANDMARKS[lm][1], shape))
        out["eyes_mid"] = 0.5 * (out["l_eye"] + out["r_eye"])
    return out


def _untwisted(q: np.ndarray, axis: np.ndarray) -> np.ndarray:
    """Local rotations ``(F, 4)`` without their twist about ``axis`` (the swing alone)."""
    a = np.asarray(axis, float) / np.linalg.norm(axis)
    twist = Q.normalize(np.concatenate([q[:, :1], (q[:, 1:] @ a)[:, None] * a], axis=-1))
    return Q.normalize(Q.mul(q, Q.conjugate(twist)))


def world_rotations(
    prof: RigProfile,
    pts,
    wrot,
    idx,
    cq,
    strategy: RetargetStrategy,
    hands: set[str],
) -> tuple[np.ndarray, list, list, dict]:
    """Canonical world rotations (F, 22, 4), the per-joint constant alignment ``R`` with
    ``G_c ~ G_s R`` (None for joints the rig lacks), the joints whose rotation the body
    defines (:mod:`engine.motion.retarget_body`, with the strategy's ``body_twist``) and,
    among those, the joints a documented rule defined (:data:`engine.motion.retarget_body.RULES`)
    with the rule's name."""
    n = wrot.shape[0]
    frames = RF.bone_frames(pts) if prof.align else {}
    limbs = RF.limb_alignments(pts, {c: wrot[:, idx[s]] for c, s in prof.joints.items()}) if prof.align else {}
    tpose = Q.conjugate(cq)  # zero pose taken as the T-pose: G_c = C G_src C^-1 = G_s C^-1
    align: list = [None] * sk.NUM_JOINTS
    aligned: dict[str, np.ndarray] = {}
    for name, src in prof.joints.items():
        g = wrot[:, idx[src]]
        if name in limbs:
            r = limbs[name]
        elif name in frames:
            r = RF.alignment(g, frames[name], _CANON_FRAMES[name])
        else:
            r = tpose
        align[sk.JOINT_INDEX[name]] = r
        aligned[name] = Q.mul(g, np.broadcast_to(r, g.shape))
    body: dict[str, np.ndarray] = {}
    body_twist = prof.align and strategy.body_twist
    if body_twist:
        straight: dict[str, np.ndarray] = {
            j: Q.rotate(
                Q.mul(aligned[j], np.broadcast_to(_BODY_FRAMES[j], aligned[j].shape)),
                np.broadcast_to([0.0, 1.0, 0.0], (n, 3)),
            )
            for j in ("lshoulder", "rshoulder")
            if j in aligned
        }
        loose = {f"{s}_{k}" for s in "lr" if s not in hands for k in ("index", "pinky", "hand_mid")}
        body_pts = {k: v for k, v in pts.items() if k not in loose}
        extra = rule_points(pts, aligned, wrot, idx, prof, hands)
        body_pts.update(extra)
        body = {
            j: q for j, q in RB.body_rotations(body_pts, straight, strategy.sole_toe_tips).items() if j in prof.joints
        }
        rules = {j: r for j, r in RB.rule_joints(extra).items() if j in body}
    else:
        rules = {}
    glob = np.zeros((n, sk.NUM_JOINTS, 4))
    for j, name in enumerate(sk.JOINT_NAMES):
        if name in body:
            g = wrot[:, idx[prof.joints[name]]]
            glob[:, j] = body[name]
            align[j] = RF.mean_rotation(Q.mul(Q.conjugate(g), body[name]), np.ones(n))
        elif body_twist and name in ("lwrist", "rwrist") and name in aligned:
            body[name] = glob[:, j] = Q.mul(
                glob[:, sk.PARENTS[j]],
                _untwisted(Q.mul(Q.conjugate(glob[:, sk.PARENTS[j]]), aligned[name]), sk.END_SITES[name]),
            )
            g = wrot[:, idx[prof.joints[name]]]
            align[j] = RF.mean_rotation(Q.mul(Q.conjugate(g), glob[:, j]), np.ones(n))
            rules[name] = "no twist"
        elif name in aligned:
            glob[:, j] = aligned[name]
        else:
            glob[:, j] = glob[:, sk.PARENTS[j]]  # joint the rig lacks: identity local rotation
    return glob, align, [j for j in RB.BODY_JOINTS if j in body], rules


def straightened_offsets(
    raw: RawBVH,
    prof: RigProfile,
    elbows: bool = True,
    knees: bool = False,
) -> tuple[np.ndarray, dict]:
    """The source's OFFSETs ``(J, 3)`` and end sites with each elbow (``elbows``) and knee
    (``knees``) straight in the zero pose, for a rig whose zero pose stands for a T-pose with
    straight limbs (``straight_elbows``, ``straight_knees``).

    The wrist (ankle) OFFSET is turned onto the direction of the elbow's (knee's), its
    length kept, and the hand (foot) below it (joints and end sites) turns with it, so it
    keeps its angle to the forearm (shin). In the zero pose every joint has its parent's
    axes, so the OFFSETs compare directly; only an end joint that is a direct child of the
    middle one is turned. With neither, the file's own OFFSETs and end sites."""
    off, ends = raw.offsets.copy(), {j: np.array(v, float) for j, v in raw.end_sites.items()}
    for s in ("l", "r"):
        limbs = [(f"{s}elbow", f"{s}wrist")] * elbows + [(f"{s}knee", f"{s}ankle")] * knees
        for mid, end in limbs:
            if mid not in prof.joints or end not in prof.joints:
                continue
            m, e = raw.names.index(prof.joints[mid]), raw.names.index(prof.joints[end])
            if raw.parents[e] != m:
                continue
            line = off[m] + off[e] if mid.endswith("knee") else off[m]
            if mid.endswith("knee"):  # the whole leg straight along its hip-to-ankle line
                off[m] = Q.rotate(Q.from_to(off[m], line), off[m])
            turn = Q.from_to(off[e], line)
            below = {e}
            for j in range(e + 1, len(raw.names)):  # BVH order: descendants follow their parent
                if raw.parents[j] in below:
                    below.add(j)
                    off[j] = Q.rotate(turn, off[j])
            for j in below:
                if j in ends:
                    ends[j] = Q.rotate(turn, ends[j])
            off[e] = Q.rotate(turn, off[e])
    return off, ends
