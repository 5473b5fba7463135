"""How a clip's joints rotate: hinge axes and bone twist, per joint.

Used to check that a retargeted clip rotates its joints like the canonical rig's own
clips do (a knee bends about its local x axis with only a few degrees of twist), not
only that its positions are right.

* **Twist** of a joint's local rotation ``q`` about its bone: the swing-twist
  decomposition of ``q`` about the bone's rest direction in the joint's frame (the
  offset of its child), as a signed angle in degrees.
* **Hinge axis** of a joint: the dominant direction of the rotation vectors
  ``log(q_ref^-1 q(t))`` over the clip (principal component weighted by angle), in
  the joint's own local frame; ``q_ref`` is the clip's mean local rotation.
"""

from __future__ import annotations

import numpy as np

from engine import skeleton as sk
from engine.kinematics import quaternion as Q

#: Child whose offset gives each joint's bone direction (leaf joints use their end site).
BONE_CHILD: dict[str, str] = {
    "lhip": "lknee",
    "lknee": "lankle",
    "lankle": "ltoe",
    "rhip": "rknee",
    "rknee": "rankle",
    "rankle": "rtoe",
    "lowerback": "upperback",
    "upperback": "chest",
    "chest": "lowerneck",
    "lowerneck": "upperneck",
    "lclavicle": "lshoulder",
    "lshoulder": "lelbow",
    "lelbow": "lwrist",
    "rclavicle": "rshoulder",
    "rshoulder": "relbow",
    "relbow": "rwrist",
}


def bone_axis(offsets: np.ndarray, joint: str) -> np.ndarray:
    """Unit direction (3,) of ``joint``'s bone in its own rest frame."""
    child = BONE_CHILD.get(joint)
    v = offsets[sk.JOINT_INDEX[child]] if child else sk.END_SITES[joint]
    return v / np.linalg.norm(v)


def joint_axis(joint: str) -> np.ndarray:
    """Unit bone direction (3,) of ``joint`` in its own canonical rest frame
    (:func:`bone_axis` on the canonical offsets); up (+Z) for the pelvis and for a joint
    with neither a child bone nor an end site."""
    if joint != "root" and (joint in BONE_CHILD or joint in sk.END_SITES):
        return bone_axis(sk.REST_OFFSETS, joint)
    return np.array([0.0, 0.0, 1.0])


def twist_deg(q: np.ndarray, axis: np.ndarray) -> np.ndarray:
    """Signed twist angle (degrees) of rotations ``q (..., 4)`` about unit ``axis (3,)``."""
    proj = (q[..., 1:] * axis).sum(-1)
    ang = 2.0 * np.arctan2(proj, q[..., 0])
    return np.degrees((ang + np.pi) % (2 * np.pi) - np.pi)


def hinge_axis(q: np.ndarray, about_zero: bool = False) -> tuple[np.ndarray, float]:
    """Dominant rotation axis (3,) of local rotations ``q (F, 4)`` and its share of the motion.

    Rotation vectors are taken relative to the clip's mean rotation, or to the zero
    rotation with ``about_zero`` (for a joint whose zero pose is straight, so that a
    knee kept bent still shows its hinge). Returns the unit axis, in the joint's frame,
    and the fraction (0..1) of the squared rotation-vector magnitude it explains (1 = a
    perfect hinge)."""
    ref = np.array([1.0, 0.0, 0.0, 0.0]) if about_zero else _mean(q)
    d = Q.mul(Q.conjugate(ref)[None], q)
    d = np.where(d[:, :1] < 0, -d, d)
    half = np.arccos(np.clip(d[:, 0], -1.0, 1.0))
    s = np.sin(half)
    rv = np.where(s[:, None] > 1e-9, d[:, 1:] / np.maximum(s, 1e-9)[:, None] * (2 * half)[:, None], 0.0)
    cov = rv.T @ rv
    w, v = np.linalg.eigh(cov)
    total = float(w.sum())
    return v[:, -1], (float(w[-1] / total) if total > 0 else 0.0)


def _mean(q: np.ndarray) -> np.ndarray:
    q = np.where(((q * q[0]).sum(-1) < 0)[:, None], -q, q)
    return Q.normalize(q.mean(0))


def joint_report(local_rot: np.ndarray, offsets: np.ndarray) -> dict[str, dict[str, float | list[float]]]:
    """Per joint: median and 90th-percentile |twist| (degrees), hinge axis and its share."""
    out: dict[str, dict[str, float | list[float]]] = {}
    for name in BONE_CHILD:
        j = sk.JOINT_INDEX[name]
        tw = twist_deg(local_rot[:, j], bone_axis(offsets, name))
        axis, share = hinge_axis(local_rot[:, j], about_zero=True)
        out[name] = {
            "twist_median": float(np.median(tw)),
            "twist_abs_p90": float(np.percentile(np.abs(tw), 90)),
            "hinge": [round(float(a), 3) for a in axis],
            "hinge_share": round(share, 3),
        }
    return out


def limb_hinge(g_parent: np.ndarray, g_child: np.ndarray, bend: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Hinge axis of a limb joint (knee, elbow) in the parent's and in the child's frame.

    The axis is the dominant rotation axis of the child relative to the parent
    (:func:`hinge_axis` of ``g_parent^-1 g_child`` about the zero rotation: rigs' zero
    poses have straight limbs), in the child's frame; in the
    parent's frame it is that axis turned by the clip's mean relative rotation. Its
    sign is the one of the bend direction ``bend (F, 3)``, world vectors
    ``(p_b - p_a) x (p_c - p_b)`` (so that it agrees between rigs).

    Parameters
    ----------
    g_parent, g_child : ndarray (F, 4)
        World rotations of the upper and lower limb joints.
    bend : ndarray (F, 3)
        World bend vectors.

    Returns
    -------
    in_parent, in_child : ndarray (3,)
        Unit axes.
    """
    rel = Q.mul(Q.conjugate(g_parent), g_child)
    axis, _ = hinge_axis(rel, about_zero=True)
    in_parent = Q.rotate(_mean(rel), axis)
    hp = Q.rotate(Q.conjugate(g_parent), bend).sum(0)
    if float(in_parent @ hp) < 0:
        axis, in_parent = -axis, -in_parent
    return in_parent, axis


def reference_axes(reports: dict[str, dict]) -> dict[str, np.ndarray]:
    """Mean hinge axis of each joint over the canonical clips (signs made to agree)."""
    axes = {}
    for joint in BONE_CHILD:
        h = np.array([r[joint]["hinge"] for r in reports.values()], float)
        h *= np.sign(h @ h[0])[:, None]
        axes[joint] = h.mean(0) / np.linalg.norm(h.mean(0))
    return axes


def summarize(groups: dict[str, dict[str, dict]], canonical: str) -> dict[str, dict[str, dict]]:
    """Compare groups of clips (``{group: {clip: joint_report}}``) with the canonical group.

    Returns ``{joint: {group: {clips, twist_median: [lo, hi], twist_abs_p90_max,
    hinge_alignment_min, hinge_alignment_median}}}``: the range of the clips' median twist
    (degrees) and the |cos| between each clip's hinge axis and the canonical clips' mean one.
    """
    ref = reference_axes(groups[canonical])
    table: dict[str, dict[str, dict]] = {}
    for joint in BONE_CHILD:
        for group, reports in groups.items():
            med = [r[joint]["twist_median"] for r in reports.values()]
            align = [abs(float(np.dot(r[joint]["hinge"], ref[joint]))) for r in reports.values()]
            table.setdefault(joint, {})[group] = {
                "clips": len(reports),
                "twist_median": [round(min(med), 1), round(max(med), 1)],
                "twist_abs_p90_max": round(max(r[joint]["twist_abs_p90"] for r in reports.values()), 1),
                "hinge_alignment_min": round(min(align), 3),
                "hinge_alignment_median": round(float(np.median(align)), 3),
            }
    return table
