"""What retargeting measures on a clip: bone offsets, standing height, toe tips and floor.

:func:`measure_offsets` gives the per-clip bone offsets along the source chain (the
subject's true proportions), :func:`standing_height` and :func:`clip_height` the
subject's height measured alike on the source and the canonical clip, :func:`toe_tips`
the source's toe tips in the canonical toe frames, and :func:`refloor` puts the clip's
feet on the floor (:mod:`engine.motion.retarget`).
"""

from __future__ import annotations

import numpy as np

from engine import skeleton as sk
from engine.kinematics import quaternion as Q
from engine.kinematics.fk import fk
from engine.motion.clip import Motion

_TOE_HEIGHT = 0.045  # canonical toe joint height above the floor when standing (metres)


def measure_offsets(pts: dict[str, np.ndarray], glob: np.ndarray, leg_scale: float) -> np.ndarray:
    """Per-clip bone offsets (22, 3), metres, measured along the source chain.

    A mapped joint's offset is the mean, over the clip, of the vector from its nearest
    mapped ancestor, expressed in that ancestor's canonical frame; canonical joints
    the rig lacks between two mapped ones share that vector in proportion to their
    canonical lengths (they have identity local rotations, so they share the frame);
    a missing leaf (toes) gets the canonical offset times ``leg_scale``."""
    off = sk.REST_OFFSETS * leg_scale
    for j in range(1, sk.NUM_JOINTS):
        name = sk.JOINT_NAMES[j]
        if name not in pts:
            continue
        chain = [j]
        a = sk.PARENTS[j]
        while sk.JOINT_NAMES[a] not in pts:
            chain.append(a)
            a = sk.PARENTS[a]
        v = pts[name] - pts[sk.JOINT_NAMES[a]]
        local = Q.rotate(Q.conjugate(glob[:, a]), v).mean(0)
        lengths = np.linalg.norm(sk.REST_OFFSETS[chain], axis=-1)
        for k, length in zip(chain, lengths):
            off[k] = local * (length / lengths.sum())
    for side in ("l", "r"):  # no toe joint but a toe tip: the toe sits on the way to it
        toe, tip, ankle = f"{side}toe", f"{side}_toe_tip", sk.JOINT_INDEX[f"{side}ankle"]
        if toe not in pts and tip in pts and f"{side}ankle" in pts:
            k = sk.JOINT_INDEX[toe]
            v = Q.rotate(Q.conjugate(glob[:, ankle]), pts[tip] - pts[f"{side}ankle"]).mean(0)
            toe_len, tip_len = np.linalg.norm(sk.REST_OFFSETS[k]), np.linalg.norm(sk.END_SITES[toe])
            off[k] = v * toe_len / (toe_len + tip_len)
    off[0] = 0.0
    return off


def standing_height(head: np.ndarray, lowest: np.ndarray, skeleton: sk.Skeleton) -> float:
    """Height (m) of the subject: 95th percentile over frames of the head joint above the
    lowest foot point, plus the skeleton's head top (the head's end site). Measured the
    same way on the source and on the canonical clip, so the two compare like for like."""
    return float(np.percentile(head - lowest, 95)) + float(sk.END_SITES["upperneck"][2] * skeleton.scale)


def toe_tips(pts, local, root, skel) -> dict[str, np.ndarray]:
    """The source's toe tips ``pts`` (``(F, 3)``, metres) as offsets ``(3,)``, metres, in the
    canonical toe frames of ``local (F, 22, 4)``, ``root (F, 3)`` (mean over the clip)."""
    pos, rot = fk(local, root, skel.offsets)
    out = {}
    for side in ("l", "r"):
        if f"{side}_toe_tip" in pts:
            k = sk.JOINT_INDEX[f"{side}toe"]
            out[f"{side}toe"] = Q.rotate(Q.conjugate(rot[:, k]), pts[f"{side}_toe_tip"] - pos[:, k]).mean(0)
    return out


def clip_height(motion: Motion, toe_tips: dict[str, np.ndarray] | None = None) -> float:
    """:func:`standing_height` of a canonical clip.

    The foot points are the ankles, the toes and the toe tips: ``toe_tips`` (offsets in
    the toe frames, as :func:`retarget` measures the source's) or, by default, the
    skeleton's end sites."""
    pos, rot = motion.fk()
    low = [pos[:, sk.JOINT_INDEX[j], 2] for j in ("lankle", "rankle", "ltoe", "rtoe")]
    if toe_tips is None:
        toe_tips = {j: sk.END_SITES[j] * motion.skeleton.scale for j in ("ltoe", "rtoe")}
    for j, off in toe_tips.items():
        k = sk.JOINT_INDEX[j]
        low.append((pos[:, k] + Q.rotate(rot[:, k], np.broadcast_to(off, pos[:, k].shape)))[:, 2])
    return standing_height(pos[:, sk.JOINT_INDEX["upperneck"], 2], np.min(low, axis=0), motion.skeleton)


def refloor(motion: Motion) -> float:
    """Shift the clip vertically so its feet stand on z = 0; returns the shift (metres)."""
    pos = motion.positions()
    toes = pos[:, [sk.JOINT_INDEX["ltoe"], sk.JOINT_INDEX["rtoe"]], 2].min(axis=1)
    ground = np.percentile(toes, 2.0)
    shift = float(_TOE_HEIGHT * motion.skeleton.scale - ground)
    motion.root_pos[:, 2] += shift
    return shift
