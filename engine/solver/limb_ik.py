"""Exact steps after the latent solve (numpy): the head onto its tracker by the spine
(:func:`reach_head_local`), wrists and ankles onto theirs (:func:`reach_local`) and tracked
joints onto their trackers' rotations (:func:`adopt_local`,
with the head's turn about the neck shared with the lower neck: :func:`share_neck_twist`).

The decoder brings a tracked hand or foot within a centimetre or two of its tracker; the
rest is beyond what a 24-d latent can express in ten iterations. This step closes the
gap with the smallest change of the limb that does it, the analytic two-bone rule of IK
solvers: the middle joint (elbow, knee) bends or straightens about its current bend axis
until the limb's length from its root joint (shoulder, hip) to the end joint equals the
distance to the tracker, then the whole limb turns about its root joint onto the
tracker. The limb keeps its plane and the end joint keeps its world rotation (the
tracker's, when :func:`adopt_local` runs after). Beyond reach the limb points
straight at the tracker.

Both steps run once per solved frame on one pose, so the per-limb arithmetic is on
Python floats (the single-rotation functions of :mod:`engine.kinematics.quat_np`), and
forward kinematics runs twice in all (:func:`finish`): once for what the limbs need
(limbs do not hold each other's joints, so one placement serves them all) and once for
the result. Both passes are :func:`engine.kinematics.fk.fk` itself, whose rounding
(rotation matrices of the slightly non-unit float32 rotations the decoder gives) the
solver's history depends on: a different FK formula changes positions by ~1e-7 m, and
the next frames, through their smoothing and predictor inputs, by more.
"""

from __future__ import annotations

import math

import numpy as np

from engine import skeleton as sk
from engine.kinematics.fk import ancestors, fk, fk_joints, fk_positions
from engine.kinematics.quat_np import (
    heading,
    qaxis_angle,
    qbetween,
    qconj,
    qmul,
    qrotate,
    vcross,
    vdot,
    vnorm,
    vscale,
    vsub,
)

#: End joint -> (limb root, middle joint).
LIMBS = {
    sk.JOINT_INDEX[c]: (sk.JOINT_INDEX[a], sk.JOINT_INDEX[b])
    for a, b, c in (
        ("lshoulder", "lelbow", "lwrist"),
        ("rshoulder", "relbow", "rwrist"),
        ("lhip", "lknee", "lankle"),
        ("rhip", "rknee", "rankle"),
    )
}
#: The head tracker's joint and the neck joint below it (:func:`share_neck_twist`).
HEAD, NECK = sk.JOINT_INDEX["upperneck"], sk.JOINT_INDEX["lowerneck"]
#: The joints between the hips and the head that :func:`reach_head_local` bends, hips first.
SPINE = tuple(sk.JOINT_INDEX[n] for n in ("lowerback", "upperback", "chest", "lowerneck"))
#: Passes of :func:`reach_head_local` (each pivots every spine joint once; three leave
#: the chord within 0.1 degree of a 25-degree swing's target, tests/engine/test_head_reach.py).
SPINE_PASSES = 3
#: Keep the limb this far (metres) from fully straight or folded: the bend axis and the
#: solution are ill-defined there.
_SLACK = 1e-3


#: The clavicles, which :func:`reach_local` may turn when a wrist target is beyond the arm.
CLAVICLES = frozenset(sk.JOINT_INDEX[n] for n in ("lclavicle", "rclavicle"))


#: The joints :func:`reach_head_local` moves or turns: the lower back and all above it (the
#: spine, neck, head, clavicles and arms).
CARRIED = frozenset(j for j in range(sk.NUM_JOINTS) if SPINE[0] in ancestors(sk.PARENTS, j))


# -- the steps ------------------------------------------------------------------------


def reach_local(
    local_rot: np.ndarray,
    root_pos: np.ndarray,
    offsets: np.ndarray,
    targets: dict[int, np.ndarray],
    shoulder_deg: float = 0.0,
) -> np.ndarray:
    """Move the tracked wrists / ankles onto their targets by their limbs' two bones.

    Parameters are those of :func:`adopt_local`, except that ``targets`` maps an end
    joint (a key of :data:`LIMBS`) to a world target *position* ``(3,)``, metres, and
    ``shoulder_deg``: when a wrist's target is beyond the straight arm, the clavicle
    first turns the shoulder towards it (:func:`_shoulder_turn`), by at most this many
    degrees (0: never), as a person shrugs or reaches forward with the shoulder.

    Returns
    -------
    local_rot : ndarray (22, 4)
        Changed at each limb's root and middle joint and its end joint (which keeps its
        world rotation); the rest as given, every row with ``w >= 0``.
    """
    local = np.array(local_rot, dtype=np.float64)
    root_pos = np.asarray(root_pos, dtype=np.float64)
    # limbs do not share joints, and none holds another's ancestors: one placement serves all
    pos_all, rot_all = fk(local, root_pos, offsets)
    pos_l, rot_l = pos_all.tolist(), rot_all.tolist()
    # each limb's joints, its root's parent (a clavicle turns) and that one's parent
    limb_joints = {j for c in targets for j in (*_above(LIMBS[c][0]), *LIMBS[c], c)}
    placed = {j: (tuple(pos_l[j]), tuple(rot_l[j])) for j in limb_joints}
    for c, target in targets.items():
        a, b = LIMBS[c]
        parent = sk.PARENTS[a]
        (pa, wa0), (pb, wb0), (pc, wc0) = placed[a], placed[b], placed[c]
        t = tuple(float(x) for x in target)
        l1, l2 = vnorm(vsub(pb, pa)), vnorm(vsub(pc, pb))
        if shoulder_deg > 0.0 and parent in CLAVICLES:
            pk, wk = placed[parent]
            turn_k = _shoulder_turn(pk, pa, t, l1 + l2 - _SLACK, math.radians(shoulder_deg))
            if turn_k is not None:
                pa, pb, pc = (_turned(turn_k, pk, x) for x in (pa, pb, pc))
                wa0, wb0 = qmul(turn_k, wa0), qmul(turn_k, wb0)
                wk = qmul(turn_k, wk)
                local[parent] = qmul(qconj(placed[sk.PARENTS[parent]][1]), wk)
                placed[parent] = (pk, wk)
        ta = vsub(t, pa)
        d = min(max(vnorm(ta), abs(l1 - l2) + _SLACK), l1 + l2 - _SLACK)
        u, v = vsub(pa, pb), vsub(pc, pb)
        n: tuple[float, ...] = vcross(u, v)
        sin_uv = vnorm(n)
        if sin_uv < 1e-9:  # straight or folded: bend about the middle joint's x axis
            n = qrotate(wb0, (1.0, 0.0, 0.0))
        n = vscale(n, 1.0 / vnorm(n))
        current = math.atan2(sin_uv, vdot(u, v))
        wanted = math.acos(min(max((l1 * l1 + l2 * l2 - d * d) / (2 * l1 * l2), -1.0), 1.0))
        bend = qaxis_angle(n, wanted - current)  # about n: u x v turns u towards v, so v away from u
        wb = qmul(bend, wb0)
        pc_new = tuple(p + r for p, r in zip(pb, qrotate(bend, v)))
        turn = qbetween(vsub(pc_new, pa), ta) if vnorm(ta) > 1e-9 else (1.0, 0.0, 0.0, 0.0)
        wa, wb = qmul(turn, wa0), qmul(turn, wb)
        local[a] = qmul(qconj(placed[parent][1]), wa)
        local[b] = qmul(qconj(wa), wb)
        local[c] = qmul(qconj(wb), wc0)  # the end joint keeps its world rotation
    local *= np.where(local[:, :1] < 0, -1.0, 1.0)
    return local


def _above(joint: int) -> tuple[int, ...]:
    """The parent and grandparent of ``joint`` (those that exist)."""
    parent = sk.PARENTS[joint]
    return (parent,) if parent <= 0 else (parent, sk.PARENTS[parent])


def _turned(q: tuple, pivot: tuple, p: tuple) -> tuple:
    """Point ``p`` turned by the world rotation ``q`` about ``pivot``."""
    return tuple(a + b for a, b in zip(pivot, qrotate(q, vsub(p, pivot))))


def _shoulder_turn(clavicle: tuple, shoulder: tuple, target: tuple, reach: float, most: float) -> tuple | None:
    """The world rotation about the clavicle joint that brings the shoulder within
    ``reach`` (metres) of ``target``, turning no further than ``most`` radians; None
    when the target is within reach already (or no turn brings it nearer).

    The shoulder moves on the sphere about the clavicle joint; its distance to the target
    is ``sqrt(c^2 + D^2 - 2 c D cos(phi))`` with ``c`` the clavicle's length, ``D`` the
    target's distance from the clavicle joint and ``phi`` the angle between the two, so
    the turn in the plane of the three points that takes ``phi`` to the angle giving
    ``reach`` is the smallest that does it.
    """
    cs, ct = vsub(shoulder, clavicle), vsub(target, clavicle)
    c, d = vnorm(cs), vnorm(ct)
    if c < 1e-9 or d < 1e-9 or vnorm(vsub(target, shoulder)) <= reach:
        return None
    axis = vcross(cs, ct)
    sin_phi = vnorm(axis)
    if sin_phi < 1e-9:
        return None
    phi = math.atan2(sin_phi, vdot(cs, ct))
    cos_want = (c * c + d * d - reach * reach) / (2.0 * c * d)
    angle = phi - math.acos(cos_want) if cos_want < 1.0 else phi
    if angle <= 0.0:
        return None
    return qaxis_angle(vscale(axis, 1.0 / sin_phi), min(angle, most))


def reach_head_local(
    local_rot: np.ndarray, root_pos: np.ndarray, offsets: np.ndarray, target: np.ndarray
) -> np.ndarray:
    """Turn the head (``upperneck``) towards ``target (3,)`` by the spine: local rotations
    ``(22, 4)``, changed at :data:`SPINE` only.

    With a hip tracker the root is placed by the hips, and the decoder's spine leaves a
    head tracker several centimetres off on performers whose posture it cannot express
    (preset ``4``, ``dragposer/`` clips: 7.6 cm). Each pass takes the swing that turns the
    chord from the lower back to the head onto the chord to ``target`` and gives each
    spine joint an equal share of its angle (scaled by the levers, below), about the
    same world axis; the joints pivot at different points, so :data:`SPINE_PASSES`
    passes converge on the target's direction (within 0.05 degrees after two). The
    chord's length is not a target: the bend changes it (on random poses, 3 mm median
    and under 2 cm for a 10-degree swing), and a target nearer or farther than the head
    stays off along the chord. Arms and head follow the chest and neck (their own local
    rotations are unchanged), so :func:`reach_local` of the wrists comes after.
    """
    local = np.array(local_rot, dtype=np.float64)
    root_pos = np.asarray(root_pos, dtype=np.float64)
    t = tuple(float(x) for x in target)
    for _ in range(SPINE_PASSES):
        pos, rots = fk_joints(local, root_pos, offsets, [*SPINE, HEAD])
        pts = [tuple(p) for p in pos.tolist()]
        base, head = pts[0], pts[-1]
        have, want = vsub(head, base), vsub(t, base)
        if vnorm(have) < 1e-9 or vnorm(want) < 1e-9:
            break
        axis = vcross(have, want)
        sin_a = vnorm(axis)
        if sin_a < 1e-12:  # on the chord already (or opposite it: no defined swing)
            break
        angle = math.atan2(sin_a, vdot(have, want))
        # the upper joints pivot nearer the head and move it less per degree: each turn is
        # scaled by the lower back's lever over the spine joints' mean lever
        levers = [vnorm(vsub(head, p)) for p in pts[:-1]]
        gain = vnorm(have) / max(sum(levers) / len(levers), 1e-9)
        r = qaxis_angle(vscale(axis, 1.0 / sin_a), min(gain * angle / len(SPINE), math.pi / len(SPINE)))
        world = _unit(qmul(tuple(rots[0].tolist()), qconj(tuple(local[SPINE[0]].tolist()))))  # the root's
        for j in SPINE:
            # the same world turn r at joint j, in its parent's frame: W^-1 r W; kept unit, as
            # the conjugate is the inverse of a unit quaternion only (the norms grew per pass)
            q = _unit(qmul(qmul(qmul(qconj(world), r), world), tuple(local[j].tolist())))
            local[j] = q
            world = _unit(qmul(world, q))
    local *= np.where(local[:, :1] < 0, -1.0, 1.0)
    return local


def _unit(q: tuple) -> tuple:
    n = math.sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3])
    return tuple(x / n for x in q)


def adopt_local(
    local_rot: np.ndarray, root_pos: np.ndarray, offsets: np.ndarray, targets: dict[int, np.ndarray]
) -> np.ndarray:
    """Give joints exact world rotations by changing their local rotations only.

    Parameters
    ----------
    local_rot : ndarray (22, 4)
        Local rotations (row 0 the root's world rotation).
    root_pos : ndarray (3,)
        Root position, metres.
    offsets : ndarray (22, 3)
        Bone offsets, metres.
    targets : dict
        Joint index (not the root) -> world rotation ``(4,)`` (w, x, y, z).

    Returns
    -------
    local_rot : ndarray (22, 4)
        ``local[j] = world[parent(j)]^-1 * target_j`` for the target joints, else as given:
        the target joints keep their positions, their descendants follow.
    """
    local = np.array(local_rot, dtype=np.float64)
    root_pos = np.asarray(root_pos, dtype=np.float64)
    order = sorted(targets)
    parents = [sk.PARENTS[j] for j in order]
    # one placement serves all unless a target lies above another's parent (then parents
    # come before children: the lower target sees the new rotation of the upper)
    nested = any(a in targets for p in parents for a in ancestors(sk.PARENTS, p))
    world = None if nested else fk_joints(local, root_pos, offsets, parents)[1].tolist()
    for k, j in enumerate(order):
        parent_rot = fk_joints(local, root_pos, offsets, [parents[k]])[1][0] if world is None else world[k]
        t = [float(x) for x in targets[j]]
        s = 1.0 / max(math.sqrt(t[0] * t[0] + t[1] * t[1] + t[2] * t[2] + t[3] * t[3]), 1e-12)
        q = qmul(qconj(parent_rot), (t[0] * s, t[1] * s, t[2] * s, t[3] * s))
        local[j] = q if q[0] >= 0 else tuple(-x for x in q)
    return local


def share_neck_twist(
    local_rot: np.ndarray, root_pos: np.ndarray, offsets: np.ndarray, head_target: np.ndarray, share: float
) -> np.ndarray:
    """Give the lower neck ``share`` of the head's rotation correction about the neck.

    :func:`adopt_local` turns the head (``upperneck``) onto its tracker alone, so a head
    the decoder left turned too little about the neck gets all of the missing turn in
    the head joint. In people the neck's axial turn is spread over the cervical spine
    (about half of it between the first two vertebrae, the rest below), so here the part
    of the correction ``target * head^-1`` that is a twist about the neck bone (lower
    neck to head) is split: ``share`` of it turns the lower neck about that bone, which
    moves no joint, and :func:`adopt_local` then gives the head the rest.

    Parameters
    ----------
    local_rot, root_pos, offsets
        The pose, as for :func:`adopt_local`.
    head_target : ndarray (4,)
        The head tracker's world rotation (w, x, y, z).
    share : float
        In [0, 1]; 0 leaves ``local_rot`` as given.

    Returns
    -------
    local_rot : ndarray (22, 4)
        With a new lower-neck rotation; every other row as given.
    """
    local = np.array(local_rot, dtype=np.float64)
    if share <= 0.0:
        return local
    _, rots = fk_joints(local, np.asarray(root_pos, dtype=np.float64), offsets, [NECK, HEAD])
    neck, head = tuple(rots[0].tolist()), tuple(rots[1].tolist())
    t = [float(x) for x in head_target]
    n = math.sqrt(sum(x * x for x in t))
    if not n > 1e-12:
        return local
    delta = qmul(tuple(x / n for x in t), qconj(head))  # world correction of the head
    axis: tuple[float, ...] = qrotate(neck, tuple(float(x) for x in offsets[HEAD]))
    length = vnorm(axis)
    if length < 1e-9:
        return local
    axis = vscale(axis, 1.0 / length)
    angle = 2.0 * math.atan2(vdot(delta[1:], axis), delta[0])  # signed twist, radians
    angle = (angle + math.pi) % (2.0 * math.pi) - math.pi
    turn = qaxis_angle(axis, share * angle)
    parent = qmul(neck, qconj(tuple(local[NECK].tolist())))  # the chest's world rotation
    q = qmul(qconj(parent), qmul(turn, neck))
    n = math.sqrt(vdot(q[1:], q[1:]) + q[0] * q[0])
    local[NECK] = tuple(x / n for x in (q if q[0] >= 0 else tuple(-x for x in q)))
    return local


def finish(
    local_rot: np.ndarray,
    root_pos: np.ndarray,
    offsets: np.ndarray,
    reach_targets: dict[int, np.ndarray],
    rotation_targets: dict[int, np.ndarray],
    neck_twist_share: float = 0.0,
    level: tuple[int, ...] = (),
    shoulder_deg: float = 0.0,
) -> tuple[np.ndarray, np.ndarray]:
    """:func:`reach_head_local` onto ``reach_targets[HEAD]`` when the head is among them,
    :func:`reach_local` onto the others (positions; the clavicles turning by up to
    ``shoulder_deg`` for a wrist beyond reach), then :func:`share_neck_twist`
    (with a head target and ``neck_twist_share`` > 0) and :func:`adopt_local` of
    ``rotation_targets`` and of the joints in ``level``, which take the root's heading
    (its yaw alone) as their world rotation; one forward kinematics pass for the positions.

    Returns
    -------
    local_rot : ndarray (22, 4)
    positions : ndarray (22, 3)
        Metres.
    """
    local = local_rot
    if HEAD in reach_targets:
        local = reach_head_local(local, root_pos, offsets, reach_targets[HEAD])
        reach_targets = {j: t for j, t in reach_targets.items() if j != HEAD}
    local = reach_local(local, root_pos, offsets, reach_targets, shoulder_deg) if reach_targets else local
    if level:
        flat = heading(np.asarray(local[0], dtype=np.float64))
        rotation_targets = {**{j: flat for j in level}, **rotation_targets}
    if rotation_targets:
        if neck_twist_share > 0.0 and HEAD in rotation_targets:
            local = share_neck_twist(local, root_pos, offsets, rotation_targets[HEAD], neck_twist_share)
        local = adopt_local(local, root_pos, offsets, rotation_targets)
    local = np.array(local, dtype=np.float64)
    return local, fk_positions(local, np.asarray(root_pos, dtype=np.float64), offsets)
