"""Bone frames: how a source joint's axes are matched to the canonical joint's axes.

For every canonical joint a *bone frame* is built from positions: its x axis along the
bone, its y axis from a second direction that moves rigidly with the bone. The
constant rotation between a source joint's own axes and that frame is estimated over
the clip (:func:`alignment`), and the same rule applied to the canonical skeleton
gives the canonical frame, so ``G_canonical(t) = G_source(t) R`` with one constant
``R`` per joint.

The second direction decides the bone's twist, so it must be rigid with the bone:

* thighs, shins, upper arms and forearms use the **hinge** of their limb (knee or
  elbow): the dominant axis of the lower joint's rotation relative to the upper one,
  read in each joint's own frame (:func:`limb_alignments`). On the canonical side the
  hinge is the one DragPoser's own clips show (:data:`CANON_HINGE`, measured with
  :func:`engine.motion.joint_stats.limb_hinge` on ``../shared/data/mocap/dragposer``; a test
  re-measures it), so a retargeted knee bends about the same local axis as in the
  clips the models learnt from, and the thigh carries no twist the shin undoes;
* the torso joints (pelvis, lower and upper back, chest, clavicles) all use the line from the
  pelvis to the neck and the hip or shoulder line, weighted towards frames where that
  line is upright (:func:`upright_weight`): on every rig a subject standing upright then
  has near-identity spine rotations, whatever the rig's spine segments look like (a
  frame per spine segment gives the iClone rig an 80-deg upper-back bend that the Daz
  rig, lacking that joint, does not have, and clavicles raised 20 deg more on the Daz
  rig than on the iClone one);
* the feet use the shin; the head the eye line; the hands the index-to-pinky line.

When a rule cannot be built (no eyes or fingers in the rig) the joint falls back to
the source's own axes, assuming its zero pose is a T-pose like the canonical one.
"""

from __future__ import annotations

import numpy as np

from engine import skeleton as sk
from engine.kinematics import quaternion as Q
from engine.motion.joint_stats import limb_hinge

# canonical joint -> (primary (from, [to candidates]), [secondary specs tried in order]).
# A secondary spec is ("vec", a, b) = b - a, or ("hinge", a, b, c) = (b - a) x (c - b).
# The torso joints (TORSO) share one up direction, pelvis to neck, instead of their own
# spine segments: rigs place their spine joints differently (iClone's 5-cm Spine01 points
# 20 deg forward where the canonical upper back bone leans 32 deg back), and a bone rule
# there gave the iClone upper back an 80-deg bend that the chest undid, while the Daz rig,
# which has no upper back, gave identity: two conventions the trackers cannot tell apart.
_TORSO_UP = ("root", ["lowerneck", "upperneck"])
RULES: dict[str, tuple] = {
    "root": (_TORSO_UP, [("vec", "rhip", "lhip")]),
    "lowerback": (_TORSO_UP, [("vec", "rhip", "lhip")]),
    "upperback": (_TORSO_UP, [("vec", "rshoulder", "lshoulder")]),
    "chest": (_TORSO_UP, [("vec", "rshoulder", "lshoulder")]),
    "lowerneck": (("lowerneck", ["upperneck"]), [("vec", "r_eye", "l_eye")]),
    "upperneck": (("r_eye", ["l_eye"]), [("vec", "upperneck", "eyes_mid")]),
}
for _s in ("l", "r"):
    _leg = ("hinge", f"{_s}hip", f"{_s}knee", f"{_s}ankle")
    _arm = ("hinge", f"{_s}shoulder", f"{_s}elbow", f"{_s}wrist")
    RULES.update(
        {
            f"{_s}hip": ((f"{_s}hip", [f"{_s}knee"]), [_leg]),
            f"{_s}knee": ((f"{_s}knee", [f"{_s}ankle"]), [_leg]),
            f"{_s}ankle": ((f"{_s}ankle", [f"{_s}_toe_tip", f"{_s}toe"]), [("vec", f"{_s}ankle", f"{_s}knee")]),
            f"{_s}toe": ((f"{_s}toe", [f"{_s}_toe_tip"]), [("vec", f"{_s}ankle", f"{_s}knee")]),
            f"{_s}clavicle": (_TORSO_UP, [("vec", "rshoulder", "lshoulder")]),
            f"{_s}shoulder": ((f"{_s}shoulder", [f"{_s}elbow"]), [_arm]),
            f"{_s}elbow": ((f"{_s}elbow", [f"{_s}wrist"]), [_arm]),
            f"{_s}wrist": ((f"{_s}wrist", [f"{_s}_hand_mid"]), [("vec", f"{_s}_pinky", f"{_s}_index")]),
        }
    )

#: Joints whose bone frame is the torso's (pelvis-to-neck line), see the module docstring.
TORSO = ("root", "lowerback", "upperback", "chest", "lclavicle", "rclavicle")
#: Exponent on the cosine of the torso's tilt in :func:`upright_weight`: 0.76 at 15 deg,
#: 0.32 at 30 deg, 0.06 at 45 deg.
UPRIGHT_POWER = 8


def upright_weight(up: np.ndarray) -> np.ndarray:
    """Weight ``(...,)`` of a frame by how upright the torso line ``up`` ``(..., 3)`` is
    (canonical world, Z up): ``cos(tilt) ** UPRIGHT_POWER``, 0 when it points down."""
    c = up[..., 2] / np.maximum(np.linalg.norm(up, axis=-1), 1e-9)
    return np.clip(c, 0.0, 1.0) ** UPRIGHT_POWER


#: Knee/elbow hinge axes in the local frame of each limb joint, as DragPoser's own clips
#: bend them: :func:`engine.motion.joint_stats.limb_hinge`, mean over the three example clips.
CANON_HINGE: dict[str, tuple[float, float, float]] = {
    "lhip": (0.936, 0.233, 0.264),
    "lknee": (0.947, 0.194, 0.256),
    "lshoulder": (-0.073, -0.580, -0.811),
    "lelbow": (-0.080, -0.590, -0.804),
    "rhip": (0.989, -0.112, -0.102),
    "rknee": (0.994, -0.066, -0.089),
    "rshoulder": (-0.185, 0.510, 0.840),
    "relbow": (-0.187, 0.512, 0.838),
}
#: Limbs aligned by their hinge: (upper joint, lower joint, end joint).
LIMBS = tuple((f"{s}hip", f"{s}knee", f"{s}ankle") for s in "lr") + tuple(
    (f"{s}shoulder", f"{s}elbow", f"{s}wrist") for s in "lr"
)

#: Canonical landmark offsets (metres, canonical rest pose) from their anchor joints.
CANON_LANDMARKS = {
    "l_toe_tip": ("ltoe", sk.END_SITES["ltoe"]),
    "r_toe_tip": ("rtoe", sk.END_SITES["rtoe"]),
    "l_eye": ("upperneck", np.array([0.032, -0.09, 0.07])),
    "r_eye": ("upperneck", np.array([-0.032, -0.09, 0.07])),
    "l_index": ("lwrist", np.array([0.09, -0.025, 0.0])),
    "l_pinky": ("lwrist", np.array([0.08, 0.03, 0.0])),
    "r_index": ("rwrist", np.array([-0.09, -0.025, 0.0])),
    "r_pinky": ("rwrist", np.array([-0.08, 0.03, 0.0])),
}


def frame(a: np.ndarray, b: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Rotation (quaternion ``(..., 4)``) whose x axis is ``a`` and y axis ``b`` made orthogonal.

    Also returns a reliability weight ``(...,)``: the squared sine of the angle between
    ``a`` and ``b``."""
    an = a / np.maximum(np.linalg.norm(a, axis=-1, keepdims=True), 1e-9)
    bn = b / np.maximum(np.linalg.norm(b, axis=-1, keepdims=True), 1e-9)
    y = bn - (bn * an).sum(-1, keepdims=True) * an
    w = (y * y).sum(-1)
    y = y / np.maximum(np.linalg.norm(y, axis=-1, keepdims=True), 1e-9)
    z = np.cross(an, y)
    return Q.normalize(Q.from_matrix(np.stack([an, y, z], axis=-1))), w


def add_derived(pts: dict[str, np.ndarray]) -> None:
    """Midpoints used by the rules (between the eyes, across the knuckles)."""
    if "l_eye" in pts and "r_eye" in pts:
        pts["eyes_mid"] = 0.5 * (pts["l_eye"] + pts["r_eye"])
    for s in ("l", "r"):
        if f"{s}_index" in pts and f"{s}_pinky" in pts:
            pts[f"{s}_hand_mid"] = 0.5 * (pts[f"{s}_index"] + pts[f"{s}_pinky"])


def bone_frames(pts: dict[str, np.ndarray], hinge: dict[str, np.ndarray] | None = None):
    """Bone frame ``(quaternion (F, 4), weight (F,))`` per canonical joint whose rule resolves.

    ``hinge`` gives fixed world hinge axes per joint (the canonical rest pose, where
    limbs are straight and the hinge cannot be read off positions)."""
    out = {}
    for joint, ((a0, a1s), secs) in RULES.items():
        a1 = next((c for c in a1s if c in pts), None)
        if a0 not in pts or a1 is None:
            continue
        a = pts[a1] - pts[a0]
        for sec in secs:
            if sec[0] == "vec" and sec[1] in pts and sec[2] in pts:
                q, w = frame(a, pts[sec[2]] - pts[sec[1]])
                out[joint] = (q, w * upright_weight(a)) if joint in TORSO else (q, w)
                break
            if sec[0] == "hinge" and hinge is not None and joint in hinge:
                out[joint] = frame(a, np.broadcast_to(hinge[joint], a.shape))
                break
            if sec[0] == "hinge" and all(k in pts for k in sec[1:]):
                u, v = pts[sec[2]] - pts[sec[1]], pts[sec[3]] - pts[sec[2]]
                h = np.cross(u, v)
                q, w = frame(a, h)
                bend = (h * h).sum(-1) / np.maximum((u * u).sum(-1) * (v * v).sum(-1), 1e-12)
                out[joint] = (q, w * bend)  # straight limbs say nothing about the hinge
                break
    return out


def canonical_frames(offsets: np.ndarray = sk.REST_OFFSETS) -> dict[str, np.ndarray]:
    """Bone frame (4,) of every canonical joint in the canonical rest pose (T-pose)."""
    skel = sk.Skeleton(offsets=np.asarray(offsets, float))
    rest = skel.rest_positions()
    pts = {n: rest[i][None] for i, n in enumerate(sk.JOINT_NAMES)}
    for lm, (anchor, off) in CANON_LANDMARKS.items():
        pts[lm] = (rest[sk.JOINT_INDEX[anchor]] + off)[None]
    add_derived(pts)
    hinge = {j: np.asarray(v, float) for j, v in CANON_HINGE.items()}
    return {j: q[0] for j, (q, _) in bone_frames(pts, hinge).items()}


def limb_alignments(pts: dict[str, np.ndarray], g: dict[str, np.ndarray]) -> dict[str, np.ndarray]:
    """Constant ``R`` (4,) per limb joint, from the limb's hinge in the joints' own frames.

    ``pts`` are canonical-named world points (F, 3), ``g`` the source world rotations
    (F, 4) of the mapped joints. For the upper and the lower joint of each limb the
    bone direction (mean over the clip, in the joint's frame) and the hinge axis
    (:func:`engine.motion.joint_stats.limb_hinge`) define a frame; the canonical frame is the
    canonical bone direction with :data:`CANON_HINGE`. Twist about the bone therefore
    comes only from the source's own motion about its hinge's frame."""
    out = {}
    for a, b, c in LIMBS:
        if not all(k in pts for k in (a, b, c)):
            continue
        bend = np.cross(pts[b] - pts[a], pts[c] - pts[b])
        h_parent, h_child = limb_hinge(g[a], g[b], bend)
        for joint, hinge, child in ((a, h_parent, b), (b, h_child, c)):
            bone = Q.rotate(Q.conjugate(g[joint]), pts[child] - pts[joint]).mean(0)
            src, _ = frame(bone, hinge)
            canon, _ = frame(sk.REST_OFFSETS[sk.JOINT_INDEX[child]], np.asarray(CANON_HINGE[joint]))
            out[joint] = Q.mul(src, Q.conjugate(canon))
    return out


def mean_rotation(q: np.ndarray, w: np.ndarray) -> np.ndarray:
    """Weighted mean of rotations ``(F, 4)`` that cluster together (sign-aligned average)."""
    ref = q[np.argmax(w)]
    q = np.where(((q * ref).sum(-1) < 0)[:, None], -q, q)
    return Q.normalize((q * w[:, None]).sum(0))


def alignment(g_src: np.ndarray, bone: tuple[np.ndarray, np.ndarray], canon: np.ndarray) -> np.ndarray:
    """Constant ``R`` (4,) with ``G_canonical = G_source R`` for one joint.

    ``g_src`` (F, 4) are the source joint's world rotations, ``bone`` its bone frames
    and weights over the clip, ``canon`` the canonical rest bone frame."""
    f, w = bone
    a = mean_rotation(Q.mul(Q.conjugate(g_src), f), w + 1e-6)
    return Q.mul(a, Q.conjugate(canon))
