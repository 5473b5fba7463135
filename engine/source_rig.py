"""Write a canonical motion back onto the rig of the BVH file it came from.

:func:`engine.retarget.retarget` turns a source joint's world rotation into the
canonical one with one constant rotation per joint, ``G_c = C G_s C^-1 R`` (``C`` the
change of axes, ``R`` the joint's alignment, both in the
:class:`~engine.retarget.RetargetReport`). Writing back inverts it: every source joint
mapped to a canonical joint gets ``G_s = C^-1 G_c R^-1``; joints outside the 22
(fingers, twist bones, eyes, ``LHipJoint``...) keep their *rest rotation*, the mean
local rotation of the source clip, and their children follow. The root's position
undoes the re-flooring, the change of axes and the unit. The result has the source's
own hierarchy, OFFSETs, channel layout and Euler orders, so it opens on the user's
character in Blender or any BVH tool; its frame rate is the motion's (60 fps).
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np
from pymotion.io.bvh import BVH as _PymotionBVH

from engine import skeleton as sk
from engine.atomic import atomic_path
from engine.bvh import RawBVH
from engine.errors import UserError
from engine.kinematics import quaternion as Q
from engine.kinematics.fk import fk
from engine.motion import Motion


def _mean_local(q: np.ndarray) -> np.ndarray:
    """Sign-aligned mean rotation per joint: ``(F, J, 4)`` -> ``(J, 4)``."""
    ref = q[:1]
    q = np.where(((q * ref).sum(-1) < 0)[..., None], -q, q)
    return Q.normalize(q.mean(0))


def source_rig_pose(motion: Motion, raw: RawBVH, report) -> tuple[np.ndarray, np.ndarray]:
    """Local rotations ``(F, J, 4)`` and local positions ``(F, J, 3)`` of the source rig.

    Positions are in the file's units: the root's holds its position channels (as
    the file writes them), other joints their channel values or OFFSET."""
    prof = report.profile
    if prof is None or report.align is None or report.basis is None:
        raise UserError(f"{raw.path}: this motion carries no retargeting record; load it with engine.retarget")
    n, nj = len(motion), len(raw.names)
    pos_c, glob_c = motion.fk()
    cqi = Q.conjugate(Q.from_matrix(report.basis))
    src_local = raw.local_quaternions()[report.skip:]
    rest_rot = _mean_local(src_local)
    rest_pos = raw.positions[report.skip:].mean(0)
    canon_of = {src: sk.JOINT_INDEX[c] for c, src in prof.joints.items()}
    glob = np.zeros((n, nj, 4))
    local = np.zeros((n, nj, 4))
    for j, name in enumerate(raw.names):
        p = raw.parents[j]
        k = canon_of.get(name)
        if k is not None and report.align[k] is not None:
            g = Q.mul(cqi, Q.mul(glob_c[:, k], Q.conjugate(report.align[k])))
            glob[:, j] = g
            local[:, j] = g if p < 0 else Q.mul(Q.conjugate(glob[:, p]), g)
        else:
            local[:, j] = rest_rot[j]
            glob[:, j] = local[:, j] if p < 0 else Q.mul(glob[:, p], local[:, j])
    positions = np.repeat(rest_pos[None], n, axis=0)
    # world position the mapped root must reach, back in source axes and units
    target = pos_c[:, 0] - np.array([0.0, 0.0, report.floor_shift])
    target = target @ report.basis / prof.units_to_m
    root_src = raw.names.index(prof.joints["root"])
    placed, _ = fk(local, np.zeros((n, 3)), raw.offsets, list(raw.parents))  # source root at the origin
    root = target - placed[:, root_src]
    positions[:, 0] = root - raw.offsets[0] if prof.root_channels_relative_to_offset else root
    return Q.normalize(local), positions


def save_on_source_rig(path: str | Path, motion: Motion, raw: RawBVH, report) -> None:
    """Write ``motion`` onto ``raw``'s hierarchy as a BVH file, atomically (see module docs).

    Raises
    ------
    UserError
        If a joint of the source has a channel layout BVH writers cannot reproduce
        (not 3 rotations, or 3 positions + 3 rotations).
    """
    for name, chans in zip(raw.names, raw.channels):
        rot = [c for c in chans if c.lower().endswith("rotation")]
        if len(rot) != 3 or len(chans) not in (3, 6):
            raise UserError(f"{raw.path}: joint {name} has channels {' '.join(chans)}; "
                            "only 3 rotations or 3 positions + 3 rotations can be written back")  # fmt: skip
    local, positions = source_rig_pose(motion, raw, report)
    order = np.asarray(raw.rot_order)
    euler = np.degrees(Q.to_euler(local, np.broadcast_to(order, local.shape[:-1] + (3,))))
    euler = (euler + 180.0) % 360.0 - 180.0
    ends = sorted(raw.end_sites.items())
    writer = _PymotionBVH()
    writer.data = {
        "filename": Path(path).stem,
        "names": np.array(raw.names),
        "offsets": raw.offsets.copy(),
        "end_sites": np.array([off for _, off in ends]).reshape(-1, 3),
        "end_sites_parents": np.array([j for j, _ in ends], dtype=int),
        "parents": np.array([0, *raw.parents[1:]]),  # pymotion marks the root as its own parent
        "rot_order": order,
        "channels": np.array([len(c) for c in raw.channels]),
        "positions": positions,
        "rotations": euler,
        "frame_time": 1.0 / float(motion.fps),
    }
    path = Path(path)
    with atomic_path(path) as tmp:
        writer.save(str(tmp))
        with open(tmp, "rb+") as fh:
            os.fsync(fh.fileno())
