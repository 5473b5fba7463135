"""Canonical world rotations of a source clip: body-defined where the body defines them.

:func:`world_rotations` gives every mapped joint one constant alignment ``R``
(``G_c = G_s R``, :mod:`engine.motion.retarget_frames`) and, from retarget version 4, replaces
the rotation of the joints the body defines (:mod:`engine.motion.retarget_body`) by their
body-defined one; ``R`` is then the mean of ``G_s^-1 G_c`` over the clip, which writing
back onto the source rig uses (:mod:`engine.motion.write_back`).
"""

from __future__ import annotations

import numpy as np

from engine.motion import retarget_body as RB
from engine.motion import retarget_frames as RF
from engine import skeleton as sk
from engine.motion.bvh import RawBVH
from engine.kinematics import quaternion as Q
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
        if wrist and all(k in raw.names and raw.parents[raw.names.index(k)] == raw.names.index(wrist) for k in knuckles):
            out.add(s)
    return out


def world_rotations(prof: RigProfile, pts, wrot, idx, cq, version: int, hands: set[str],
                     ) -> tuple[np.ndarray, list, list]:  # fmt: skip
    """Canonical world rotations (F, 22, 4), the per-joint constant alignment ``R`` with
    ``G_c ~ G_s R`` (None for joints the rig lacks) and the joints whose rotation the body
    defines (:mod:`engine.motion.retarget_body`, from version 4)."""
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
    if prof.align and version >= 4:
        straight = {j: Q.rotate(Q.mul(aligned[j], np.broadcast_to(_BODY_FRAMES[j], aligned[j].shape)),
                                np.broadcast_to([0.0, 1.0, 0.0], (n, 3)))
                    for j in ("lshoulder", "rshoulder") if j in aligned}  # fmt: skip
        loose = {f"{s}_{k}" for s in "lr" if s not in hands for k in ("index", "pinky", "hand_mid")}
        body_pts = {k: v for k, v in pts.items() if k not in loose}
        body = {j: q for j, q in RB.body_rotations(body_pts, straight).items() if j in prof.joints}
    glob = np.zeros((n, sk.NUM_JOINTS, 4))
    for j, name in enumerate(sk.JOINT_NAMES):
        if name in body:
            g = wrot[:, idx[prof.joints[name]]]
            glob[:, j] = body[name]
            align[j] = RF.mean_rotation(Q.mul(Q.conjugate(g), body[name]), np.ones(n))
        elif name in aligned:
            glob[:, j] = aligned[name]
        else:
            glob[:, j] = glob[:, sk.PARENTS[j]]  # joint the rig lacks: identity local rotation
    return glob, align, [j for j in RB.BODY_JOINTS if j in body]


def straightened_offsets(raw: RawBVH, prof: RigProfile) -> tuple[np.ndarray, dict]:
    """The source's OFFSETs ``(J, 3)`` and end sites with each elbow straight in the zero
    pose, for a rig whose zero pose stands for a T-pose with straight arms (``straight_elbows``).

    The wrist OFFSET is turned onto the direction of the elbow's, its length kept, and the
    hand below it (joints and end sites) turns with it, so the hand keeps its angle to the
    forearm. In the zero pose every joint has its parent's axes, so the OFFSETs compare
    directly; only a wrist that is a direct child of the elbow is turned. Knees are left
    as drawn: the shin's twist the body defines differs from the source's, and on a shin
    drawn bent that would move the written-back ankle (docs/skeleton.md)."""
    off, ends = raw.offsets.copy(), {j: np.array(v, float) for j, v in raw.end_sites.items()}
    for s in ("l", "r"):
        for mid, end in ((f"{s}elbow", f"{s}wrist"),):
            if mid not in prof.joints or end not in prof.joints:
                continue
            m, e = raw.names.index(prof.joints[mid]), raw.names.index(prof.joints[end])
            if raw.parents[e] != m:
                continue
            turn = Q.from_to(off[e], off[m])
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
