"""What a glTF file holds, built from the engine's types: a canonical :class:`Motion`, the
same motion on the rig of the BVH file it came from, and simulated tracker targets.

Every builder returns data in the studio's axes (Z up, metres); :mod:`engine.motion.gltf`
turns them into glTF's Y-up frame when it writes.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from engine import skeleton as sk
from engine.kinematics import quaternion as Q
from engine.motion.bvh import RawBVH
from engine.motion.clip import Motion
from engine.motion.gltf import Character, TrackerNodes
from engine.motion.mannequin import BONE_RADIUS, END_RADIUS, END_SHARE

#: Base colour of the main character and, in turn, of the comparison characters (linear RGBA).
RGBA = tuple[float, float, float, float]
MAIN_COLOUR: RGBA = (0.80, 0.55, 0.40, 1.0)
GHOST_COLOURS = ((0.35, 0.55, 0.85, 1.0), (0.45, 0.75, 0.40, 1.0), (0.85, 0.75, 0.30, 1.0), (0.65, 0.45, 0.80, 1.0))


def ghost_colour(k: int) -> tuple[float, float, float, float]:
    """Colour of the ``k``-th comparison character (0-based)."""
    return GHOST_COLOURS[k % len(GHOST_COLOURS)]


def _radii(named: dict[str, int], scale: float) -> dict[int, float]:
    """Capsule radii by joint index (end sites as ``-1 - owner``) for the canonical joints
    in ``named`` (canonical name -> joint index of the rig), scaled to the subject."""
    out = {j: BONE_RADIUS[c] * scale for c, j in named.items() if c in BONE_RADIUS}
    out.update({-1 - j: END_RADIUS[c] * scale for c, j in named.items() if c in END_RADIUS})
    return out


def character_of(motion: Motion, name: str = "", colour: RGBA = MAIN_COLOUR) -> Character:
    """``motion`` on the canonical 22-joint skeleton (the joints and OFFSETs its BVH has)."""
    offsets = np.asarray(motion.skeleton.offsets, float).copy()
    offsets[0] = 0.0  # the root's position lives in its channel, as in the BVH
    trans = np.repeat(offsets[None], len(motion), axis=0)
    trans[:, 0] = motion.root_pos
    scale = motion.skeleton.scale
    return Character(
        name=name,
        joints=tuple(sk.JOINT_NAMES),
        parents=tuple(sk.PARENTS),
        rest=offsets,
        translations=trans,
        rotations=Q.normalize(motion.local_rot),
        fps=float(motion.fps),
        ends={sk.JOINT_INDEX[n]: off * scale * END_SHARE[n] for n, off in sk.END_SITES.items()},
        radius=_radii(sk.JOINT_INDEX, scale),
        colour=colour,
    )


def character_on_source_rig(
    motion: Motion, raw: RawBVH, report: Any, fps: float | None = None, name: str = "", colour: RGBA = MAIN_COLOUR
) -> Character:
    """``motion`` written onto ``raw``'s hierarchy, exactly as
    :func:`engine.motion.write_back.save_on_source_rig` writes its BVH (same joints,
    names, OFFSETs, rotations, position channels, frame rate ``fps`` or the source's),
    brought into the studio's axes and metres with the rig's change of axes and unit."""
    from engine.motion.retarget import resample_motion
    from engine.motion.write_back import frame_local_offsets, source_rig_pose

    fps = float(fps or report.source_fps or motion.fps)
    start_s = motion.start / motion.fps  # a trimmed clip: the source frames it holds
    if abs(fps - motion.fps) > 1e-6:
        motion = resample_motion(motion, fps)
    local, positions = source_rig_pose(motion, raw, report, start_s)
    prof = report.profile
    if prof.root_channels_relative_to_offset:
        positions = positions.copy()
        positions[:, 0] += raw.offsets[0]  # the file's root channels count from its OFFSET
    basis, unit = np.asarray(report.basis, float), float(prof.units_to_m)
    b = np.broadcast_to(Q.from_matrix(basis), local.shape)
    index = {n: j for j, n in enumerate(raw.names)}
    named = {c: index[s] for c, s in prof.joints.items() if s in index}
    return Character(
        name=name,
        joints=tuple(raw.names),
        parents=tuple(raw.parents),
        rest=raw.offsets @ basis.T * unit,
        translations=frame_local_offsets(raw, positions) @ basis.T * unit,
        rotations=Q.normalize(Q.mul(Q.mul(b, local), Q.conjugate(b))),
        fps=fps,
        ends={j: off @ basis.T * unit for j, off in raw.end_sites.items()},
        radius=_radii(named, motion.skeleton.scale),
        colour=colour,
    )


def trackers_of(tracking: Any, floor_shift: float = 0.0) -> TrackerNodes:
    """Boxes following the tracker targets of ``tracking`` (:class:`engine.tracking.Tracking`).

    ``floor_shift`` (metres) is the retargeting's re-flooring, taken off again when the
    character is written on its source rig, so that the boxes stay on its body."""
    pos = np.asarray(tracking.positions, float) - np.array([0.0, 0.0, floor_shift])
    return TrackerNodes(
        names=tuple(tracking.joints),
        positions=pos,
        rotations=np.asarray(tracking.rotations, float),
        connected=np.asarray(tracking.connected, bool),
        fps=float(tracking.fps),
        position_only=tuple(d == 3 for d in tracking.dof),
    )
