"""A skinned mannequin built from a skeleton's rest pose, for files that carry a body (glTF).

One capsule per bone (joint to child joint, or joint to end site), with rings along the
bone so that it can bend. Each vertex is skinned to the joint that moves the bone and,
near either end, blended with the joint across the bend: at a joint both meeting
capsules are weighted half and half to the two joints, so an elbow or knee bends into
a smooth sleeve instead of two rigid pieces that cross or tear apart.

Radii follow the studio's body view (:data:`BONE_RADIUS`, metres, by the canonical
joint at the bone's child end); a rig's joints outside the 22 (fingers, twist bones)
get a quarter of their bone's length, never thicker than the bone they hang from.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

#: Capsule radius per bone, metres, keyed by the bone's child joint (SMPL-like build).
BONE_RADIUS: dict[str, float] = {
    "lhip": 0.075,
    "rhip": 0.075,
    "lknee": 0.065,
    "rknee": 0.065,
    "lankle": 0.048,
    "rankle": 0.048,
    "ltoe": 0.035,
    "rtoe": 0.035,
    "lowerback": 0.12,
    "upperback": 0.12,
    "chest": 0.13,
    "lowerneck": 0.055,
    "upperneck": 0.095,
    "lclavicle": 0.05,
    "rclavicle": 0.05,
    "lshoulder": 0.05,
    "rshoulder": 0.05,
    "lelbow": 0.042,
    "relbow": 0.042,
    "lwrist": 0.04,
    "rwrist": 0.04,
}

#: Radius of the end-site capsules (head top, hands, toes), by the joint that owns them.
END_RADIUS: dict[str, float] = {"upperneck": 0.085, "lwrist": 0.038, "rwrist": 0.038, "ltoe": 0.03, "rtoe": 0.03}

#: Share of the canonical end-site OFFSET a capsule spans: the canonical rig's end sites
#: repeat their joint's own OFFSET (a 26 cm "hand"), so the mannequin draws a hand, a
#: toe cap and a head top of plausible length instead.
END_SHARE: dict[str, float] = {"upperneck": 0.55, "lwrist": 0.35, "rwrist": 0.35, "ltoe": 0.45, "rtoe": 0.45}

AROUND = 12  # vertices around a capsule
ALONG = 8  # segments along the straight part (room for the bend's blend)
CAP = 3  # rings per end cap, the pole excluded
MIN_BONE = 1e-3  # metres: shorter bones (a static helper joint at its parent) get no capsule
MIN_RADIUS = 0.006  # metres


@dataclass(frozen=True)
class Bone:
    """One capsule: from joint ``joint`` to ``end`` (rest world positions, metres),
    moved by ``joint``; ``child`` is the joint at the far end (-1 for an end site)."""

    joint: int
    child: int
    start: np.ndarray
    end: np.ndarray
    radius: float


@dataclass(frozen=True)
class SkinnedMesh:
    """Triangle mesh in the rest pose with four joint influences per vertex.

    Attributes
    ----------
    positions, normals : ndarray (V, 3) float32
        Rest-pose vertices (metres) and unit normals.
    joints : ndarray (V, 4) uint16
        Joint indices (into the skeleton's joint list); unused slots are 0.
    weights : ndarray (V, 4) float32
        Their weights, summing to 1; unused slots are 0.
    indices : ndarray (K * 3,) uint32
        Triangles, counter-clockwise seen from outside.
    """

    positions: np.ndarray
    normals: np.ndarray
    joints: np.ndarray
    weights: np.ndarray
    indices: np.ndarray


def _template() -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """One capsule of radius 1 along +z: unit directions ``(T, 3)``, position along the
    bone ``s (T,)`` (0 at the start, 1 at the end), which end cap holds the vertex
    ``cap (T,)`` (-1, 0 on the straight part, +1) and triangles ``(K, 3)``."""
    lat_lo = np.linspace(-np.pi / 2, 0, CAP + 1)[1:]  # start cap, towards the equator
    lat_hi = np.linspace(0, np.pi / 2, CAP + 1)[1:-1]  # end cap, the equator excluded
    rings = [(la, 0.0, -1) for la in lat_lo[:-1]] + [(0.0, s, 0) for s in np.linspace(0, 1, ALONG + 1)]
    rings += [(la, 1.0, 1) for la in lat_hi]
    lon = np.linspace(0, 2 * np.pi, AROUND, endpoint=False)
    dirs, along, cap = [], [], []
    for lat, s, c in rings:
        ring = np.stack([np.cos(lat) * np.cos(lon), np.cos(lat) * np.sin(lon), np.full(AROUND, np.sin(lat))], -1)
        dirs.append(ring)
        along += [s] * AROUND
        cap += [c] * AROUND
    dirs += [np.array([[0.0, 0.0, -1.0]]), np.array([[0.0, 0.0, 1.0]])]
    along += [0.0, 1.0]
    cap += [-1, 1]
    n = len(rings)
    tris = []
    for r in range(n - 1):
        for k in range(AROUND):
            a, b = r * AROUND + k, r * AROUND + (k + 1) % AROUND
            tris += [[a, b, b + AROUND], [a, b + AROUND, a + AROUND]]
    bottom, top, last = n * AROUND, n * AROUND + 1, (n - 1) * AROUND
    for k in range(AROUND):
        tris.append([bottom, (k + 1) % AROUND, k])
        tris.append([top, last + k, last + (k + 1) % AROUND])
    return np.vstack(dirs), np.array(along), np.array(cap), np.array(tris)


def _frame(axis: np.ndarray) -> np.ndarray:
    """A rotation matrix whose third column is the unit ``axis``."""
    helper = np.array([0.0, 0.0, 1.0]) if abs(axis[2]) < 0.9 else np.array([1.0, 0.0, 0.0])
    e1 = np.cross(axis, helper)
    e1 /= np.linalg.norm(e1)
    return np.stack([e1, np.cross(axis, e1), axis], axis=1)


def _smooth(x: np.ndarray) -> np.ndarray:
    x = np.clip(x, 0.0, 1.0)
    return x * x * (3.0 - 2.0 * x)


def bones_of(
    rest: np.ndarray, parents: tuple[int, ...], ends: dict[int, np.ndarray], radius: dict[int, float]
) -> list[Bone]:
    """Capsules of a skeleton in its rest pose.

    Parameters
    ----------
    rest : ndarray (J, 3)
        Rest world positions, metres.
    parents : tuple of int
        Parent of each joint (-1 for the root).
    ends : dict of int to ndarray (3,)
        End-site offsets (metres, in the rest pose's axes) by the joint that owns them.
    radius : dict of int to float
        Known radii by the joint at a bone's far end (an end site by its owner's index,
        negated and minus one: ``-1 - j``); others are derived from the bone's length.
    """
    bones: list[Bone] = []
    along_parent: dict[int, float] = {}  # radius of the bone ending at each joint
    segments = [(p, j, rest[j]) for j, p in enumerate(parents) if p >= 0]
    segments += [(j, -1, rest[j] + off) for j, off in sorted(ends.items())]
    for p, child, tip in segments:
        length = float(np.linalg.norm(tip - rest[p]))
        key = child if child >= 0 else -1 - p
        known = radius.get(key)
        limit = along_parent.get(p, known or 0.05)
        r = known if known is not None else float(np.clip(0.25 * length, MIN_RADIUS, max(limit, MIN_RADIUS)))
        if child >= 0:
            along_parent[child] = r
        if length >= MIN_BONE:
            bones.append(Bone(p, child, rest[p], tip, r))
    return bones


def skinned_mannequin(bones: list[Bone], parents: tuple[int, ...]) -> SkinnedMesh:
    """The mannequin of ``bones`` (:func:`bones_of`) with smooth weights (module docs)."""
    dirs, along, cap, tris = _template()
    pos, nrm, jnt, wgt, idx = [], [], [], [], []
    offset = 0
    for b in bones:
        d = b.end - b.start
        length = float(np.linalg.norm(d))
        frame = _frame(d / length)
        normals = dirs @ frame.T
        pos.append(b.start + along[:, None] * d + b.radius * normals)
        nrm.append(normals)
        # blend zones: about a radius at each end, at most 45% of the bone
        zone = min(b.radius, 0.45 * length) / length
        up = parents[b.joint]
        w_up = 0.5 * (1.0 - _smooth(along / zone)) if up >= 0 else np.zeros_like(along)
        w_down = 0.5 * _smooth((along - (1.0 - zone)) / zone) if b.child >= 0 else np.zeros_like(along)
        w_up = np.where(cap == 1, 0.0, w_up)
        w_down = np.where(cap == -1, 0.0, w_down)
        w = np.stack([1.0 - w_up - w_down, w_up, w_down, np.zeros_like(along)], -1)
        j = np.array([b.joint, max(up, 0), max(b.child, 0), 0])
        jj = np.where(w > 0, j[None], 0)
        jnt.append(jj)
        wgt.append(w)
        idx.append(tris + offset)
        offset += len(dirs)
    normals = np.vstack(nrm).astype(np.float32)
    normals /= np.linalg.norm(normals, axis=1, keepdims=True)
    weights = np.vstack(wgt).astype(np.float32)
    weights[:, 0] = 1.0 - weights[:, 1:].sum(1)  # sum to 1 in float32
    return SkinnedMesh(
        positions=np.vstack(pos).astype(np.float32),
        normals=normals,
        joints=np.vstack(jnt).astype(np.uint16),
        weights=weights,
        indices=np.vstack(idx).astype(np.uint32).ravel(),
    )
