"""Exact steps after the latent solve (numpy): wrists and ankles onto their trackers
(:func:`reach`) and tracked joints onto their trackers' rotations (:func:`adopt_rotations`).

The decoder brings a tracked hand or foot within a centimetre or two of its tracker; the
rest is beyond what a 24-d latent can express in ten iterations. This step closes the
gap with the smallest change of the limb that does it, the analytic two-bone rule of IK
solvers: the middle joint (elbow, knee) bends or straightens about its current bend axis
until the limb's length from its root joint (shoulder, hip) to the end joint equals the
distance to the tracker, then the whole limb turns about its root joint onto the
tracker. The limb keeps its plane and the end joint keeps its world rotation (the
tracker's, when :func:`engine.solver.pose.adopt_rotations` runs after). Beyond reach the
limb points straight at the tracker.
"""

from __future__ import annotations

import math

import numpy as np

from engine import skeleton as sk
from engine.kinematics import quat_np as QN
from engine.kinematics.fk import fk

#: End joint -> (limb root, middle joint).
LIMBS = {sk.JOINT_INDEX[c]: (sk.JOINT_INDEX[a], sk.JOINT_INDEX[b])
         for a, b, c in (("lshoulder", "lelbow", "lwrist"), ("rshoulder", "relbow", "rwrist"),
                         ("lhip", "lknee", "lankle"), ("rhip", "rknee", "rankle"))}  # fmt: skip
#: Keep the limb this far (metres) from fully straight or folded: the bend axis and the
#: solution are ill-defined there.
_SLACK = 1e-3


def _axis_angle(axis: np.ndarray, angle: float) -> np.ndarray:
    return np.concatenate(([math.cos(angle / 2)], math.sin(angle / 2) * axis))


def _between(u: np.ndarray, v: np.ndarray) -> np.ndarray:
    """Smallest rotation (4,) taking direction ``u`` onto direction ``v``."""
    u, v = u / np.linalg.norm(u), v / np.linalg.norm(v)
    q = np.concatenate(([1.0 + float(u @ v)], np.cross(u, v)))
    n = np.linalg.norm(q)
    if n < 1e-9:  # opposite: any perpendicular axis
        perp = np.cross(u, [1.0, 0.0, 0.0] if abs(u[0]) < 0.9 else [0.0, 1.0, 0.0])
        return _axis_angle(perp / np.linalg.norm(perp), math.pi)
    return q / n


def reach(local_rot: np.ndarray, root_pos: np.ndarray, offsets: np.ndarray,
          targets: dict[int, np.ndarray]) -> tuple[np.ndarray, np.ndarray]:  # fmt: skip
    """Move the tracked wrists / ankles onto their targets by their limbs' two bones.

    Parameters are those of :func:`adopt_rotations`, except that ``targets`` maps an end
    joint (a key of :data:`LIMBS`) to a world target *position* ``(3,)``, metres.

    Returns
    -------
    local_rot : ndarray (22, 4)
        Changed at each limb's root and middle joint and its end joint (which keeps its
        world rotation); the rest as given.
    positions : ndarray (22, 3)
        FK of the result, metres.
    """
    local = np.array(local_rot, dtype=np.float64)
    root_pos = np.asarray(root_pos, dtype=np.float64)
    for c, target in targets.items():
        a, b = LIMBS[c]
        pos, world = fk(local, root_pos, offsets)
        pa, pb, pc = pos[a], pos[b], pos[c]
        t = np.asarray(target, dtype=np.float64)
        l1, l2 = np.linalg.norm(pb - pa), np.linalg.norm(pc - pb)
        d = float(np.clip(np.linalg.norm(t - pa), abs(l1 - l2) + _SLACK, l1 + l2 - _SLACK))
        u, v = pa - pb, pc - pb
        n = np.cross(u, v)
        if np.linalg.norm(n) < 1e-9:  # straight or folded: bend about the middle joint's x axis
            n = QN.rotate(world[b], np.array([1.0, 0.0, 0.0]))
        n = n / np.linalg.norm(n)
        current = math.atan2(float(np.linalg.norm(np.cross(u, v))), float(u @ v))
        wanted = math.acos(float(np.clip((l1 * l1 + l2 * l2 - d * d) / (2 * l1 * l2), -1.0, 1.0)))
        bend = _axis_angle(n, wanted - current)  # about n: u x v turns u towards v, so v away from u
        wb = QN.mul(bend, world[b])
        pc_new = pb + QN.rotate(bend, v)
        turn = _between(pc_new - pa, t - pa) if np.linalg.norm(t - pa) > 1e-9 else np.array([1.0, 0, 0, 0])
        wa, wb = QN.mul(turn, world[a]), QN.mul(turn, wb)
        parent = sk.PARENTS[a]
        local[a] = QN.mul(QN.conjugate(world[parent]), wa)
        local[b] = QN.mul(QN.conjugate(wa), wb)
        local[c] = QN.mul(QN.conjugate(wb), world[c])  # the end joint keeps its world rotation
    local *= np.where(local[:, :1] < 0, -1.0, 1.0)
    positions, _ = fk(local, root_pos, offsets)
    return local, positions


def adopt_rotations(local_rot: np.ndarray, root_pos: np.ndarray, offsets: np.ndarray,
                    targets: dict[int, np.ndarray]) -> tuple[np.ndarray, np.ndarray]:  # fmt: skip
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
        ``local[j] = world[parent(j)]^-1 * target_j`` for the target joints, else as given.
    positions : ndarray (22, 3)
        FK of the result: the target joints keep their positions, their descendants follow.
    """
    local = np.array(local_rot, dtype=np.float64)
    world = np.empty_like(local)
    world[0] = local[0]
    for j in range(1, sk.NUM_JOINTS):  # parents come before children
        p = sk.PARENTS[j]
        if j in targets:
            t = np.asarray(targets[j], dtype=np.float64)
            t = t / max(float(np.linalg.norm(t)), 1e-12)
            local[j] = QN.mul(QN.conjugate(world[p]), t)
            if local[j, 0] < 0:
                local[j] = -local[j]
        world[j] = QN.mul(world[p], local[j])
    positions, _ = fk(local, np.asarray(root_pos, dtype=np.float64), offsets)
    return local, positions
