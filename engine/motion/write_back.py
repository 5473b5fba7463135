"""Write a canonical motion back onto the rig of the BVH file it came from.

:func:`engine.motion.retarget.retarget` turns a source joint's world rotation into the
canonical one with one constant rotation per joint, ``G_c = C G_s C^-1 R`` (``C`` the
change of axes, ``R`` the joint's alignment, both in the
:class:`~engine.motion.retarget.RetargetReport`). Writing back inverts it: every source joint
mapped to a canonical joint gets ``G_s = C^-1 G_c R^-1``; joints outside the 22
(fingers, twist bones, eyes, ``LHipJoint``...) keep their *rest rotation*, the mean
local rotation of the source clip, and their children follow. The root's position
undoes the re-flooring, the change of axes and the unit. The result has the source's
own hierarchy, OFFSETs, channel layout and Euler orders, so it opens on the user's
character in Blender or any BVH tool. The trajectory goes on whichever joint carries it in
the source (:func:`trajectory_joint`), the other position channels keep the source's
values, and the frame rate is the source's unless another is asked for.
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np
from pymotion.io.bvh import BVH as _PymotionBVH

from engine import skeleton as sk
from engine.atomic import atomic_path
from engine.errors import UserError
from engine.kinematics import quaternion as Q
from engine.kinematics.fk import ancestors, children, fk
from engine.motion.bvh import RawBVH
from engine.motion.clip import Motion


def _mean_local(q: np.ndarray) -> np.ndarray:
    """Sign-aligned mean rotation per joint: ``(F, J, 4)`` -> ``(J, 4)``."""
    ref = q[:1]
    q = np.where(((q * ref).sum(-1) < 0)[..., None], -q, q)
    return Q.normalize(q.mean(0))


def trajectory_joint(raw: RawBVH, root: int) -> int:
    """The joint whose position channels carry the trajectory of source joint ``root``:
    ``root`` itself when it has position channels (a ``Hips`` with 6 channels under a static
    ``joint_Root``), else its nearest ancestor that has them (the file's ROOT)."""
    chain = ancestors(raw.parents, root)
    return next((j for j in chain if len(raw.channels[j]) == 6), chain[-1])


def _below(raw: RawBVH, j: int, root: int) -> bool:
    """Whether joint ``j`` is ``root`` or one of its descendants."""
    return root in ancestors(raw.parents, j)


def frame_local_offsets(raw: RawBVH, positions: np.ndarray) -> np.ndarray:
    """Per-frame local positions ``(F, J, 3)``: position channels where a joint has them
    (``positions``), its OFFSET elsewhere."""
    moving = np.array([len(c) == 6 for c in raw.channels])
    return np.where(moving[None, :, None], positions, raw.offsets[None])


def source_rig_pose(motion: Motion, raw: RawBVH, report, start_s: float = 0.0) -> tuple[np.ndarray, np.ndarray]:
    """Local rotations ``(F, J, 4)`` and local positions ``(F, J, 3)`` of the source rig.

    Positions are in the file's units, as the file writes them: the position channels of
    every joint that has them (the source's values at the same time), except that the
    joint carrying the trajectory (:func:`trajectory_joint`) takes the reconstruction's;
    joints without position channels hold their OFFSET. ``motion`` is at the frame rate
    to be written; frame i of it is at ``i / fps + start_s`` seconds into the clip as
    loaded (``start_s`` > 0 for a trimmed clip, :meth:`Motion.trim`)."""
    prof = report.profile
    if prof is None or report.align is None or report.basis is None:
        raise UserError(f"{raw.path}: this motion carries no retargeting record; load it with engine.motion.retarget")
    n, nj = len(motion), len(raw.names)
    pos_c, glob_c = motion.fk()
    cqi = Q.conjugate(Q.from_matrix(report.basis))
    src_local = raw.local_quaternions()[report.skip :]
    rest_rot = _mean_local(src_local)
    canon_of = {src: sk.JOINT_INDEX[c] for c, src in prof.joints.items()}
    # every position channel as the source has it at the same time; the one joint that
    # carries the trajectory is moved at the end so that the mapped root lands on the canonical one
    src_frame = np.rint((np.arange(n) / motion.fps + start_s) * report.source_fps).astype(int) + report.skip
    positions = raw.positions[np.clip(src_frame, 0, len(raw.positions) - 1)].copy()
    if prof.root_channels_relative_to_offset:
        positions[:, 0] += raw.offsets[0]
    local_off = frame_local_offsets(raw, positions)
    root_src = raw.names.index(prof.joints["root"])
    # canonical joint positions relative to the canonical root, in source axes and units
    want = (pos_c - pos_c[:, :1]) @ report.basis / prof.units_to_m
    rel = np.zeros((n, nj, 3))  # source joints relative to the mapped root, as they are placed
    glob = np.zeros((n, nj, 4))
    local = np.zeros((n, nj, 4))
    for j, name in enumerate(raw.names):
        p = raw.parents[j]
        k = canon_of.get(name)
        if p >= 0 and j != root_src and _below(raw, j, root_src):
            rel[:, j] = rel[:, p] + Q.rotate(glob[:, p], local_off[:, j])
        if k is not None and report.align[k] is not None:
            glob[:, j] = Q.mul(cqi, Q.mul(glob_c[:, k], Q.conjugate(report.align[k])))
        else:
            glob[:, j] = rest_rot[j] if p < 0 else Q.mul(glob[:, p], np.broadcast_to(rest_rot[j], (n, 4)))
            kids = children(raw.parents, j)
            if len(kids) == 1 and raw.names[kids[0]] in canon_of and _below(raw, j, root_src):
                # a joint folded into a canonical bone (LowerBack, Neck): swung so that the next
                # mapped joint lands where the canonical one is, its own twist kept from the rest
                c = kids[0]
                now = Q.rotate(glob[:, j], local_off[:, c])
                glob[:, j] = Q.mul(Q.from_to(now, want[:, canon_of[raw.names[c]]] - rel[:, j]), glob[:, j])
        local[:, j] = glob[:, j] if p < 0 else Q.mul(Q.conjugate(glob[:, p]), glob[:, j])
    mover = trajectory_joint(raw, root_src)
    target = pos_c[:, 0] - np.array([0.0, 0.0, report.floor_shift])
    target = target @ report.basis / prof.units_to_m  # back in source axes and units
    placed, grot = fk(local, positions[:, 0], local_off, list(raw.parents))
    delta = target - placed[:, root_src]
    up = raw.parents[mover]
    positions[:, mover] += delta if up < 0 else Q.rotate(Q.conjugate(grot[:, up]), delta)
    if prof.root_channels_relative_to_offset:
        positions[:, 0] -= raw.offsets[0]
    return Q.normalize(local), positions


def save_on_source_rig(path: str | Path, motion: Motion, raw: RawBVH, report, fps: float | None = None) -> None:
    """Write ``motion`` onto ``raw``'s hierarchy as a BVH file, atomically (see module docs).

    ``fps`` is the frame rate written (default: the source's, ``report.source_fps``);
    the motion is resampled to it (slerp). A trimmed clip (``motion.start`` > 0) is
    written as the source's frames it holds: the other position channels are those of
    the same source frames.

    Raises
    ------
    UserError
        If a joint of the source has a channel layout BVH writers cannot reproduce
        (not 3 rotations, or 3 positions + 3 rotations).
    """
    for name, chans in zip(raw.names, raw.channels):
        rot = [c for c in chans if c.lower().endswith("rotation")]
        if len(rot) != 3 or len(chans) not in (3, 6):
            raise UserError(
                f"{raw.path}: joint {name} has channels {' '.join(chans)}; "
                "only 3 rotations or 3 positions + 3 rotations can be written back"
            )
    from engine.motion.retarget import resample_motion

    fps = float(fps or report.source_fps or motion.fps)
    start_s = motion.start / motion.fps  # before resampling: the start counts the clip's frames
    if abs(fps - motion.fps) > 1e-6:
        motion = resample_motion(motion, fps)
    local, positions = source_rig_pose(motion, raw, report, start_s)
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
