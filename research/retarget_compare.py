"""Compare two canonical clips of the same take converted from different rigs.

The copies of a CMU take on different rigs start at different frames (a dropped rest
frame, a trimmed start), run at different source rates and face different global
headings. :func:`compare_clips` finds the time offset and the heading that align them
best, then measures how far their canonical motions differ: local rotations (degrees,
per joint) and root-relative joint positions with both subjects scaled to one height
(centimetres, per joint). ``research/cross_rig.py`` prints the table of every take on
several rigs; ``tests/research/test_cross_rig.py`` checks it.
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from engine import skeleton as sk
from engine.kinematics import quaternion as Q
from engine.motion.clip import Motion

#: Rate (frames/s) at which clips are compared: a copy that dropped one 120-fps rest
#: frame is half a 60-fps frame off, which this rate resolves.
COMPARE_FPS = 120.0
#: Height (metres) both subjects are scaled to before positions are compared.
COMMON_HEIGHT = 1.7
#: Largest time offset (seconds) searched between two copies.
MAX_SHIFT_S = 1.0


@dataclass
class ClipDifference:
    """How two copies of one take differ once aligned (see :func:`compare_clips`)."""

    #: Frames of ``b`` (at :data:`COMPARE_FPS`) that ``a`` starts later by.
    shift: int
    #: Rotation about +Z (degrees) applied to ``a`` to face like ``b``.
    heading_deg: float
    #: Compared frames.
    frames: int
    #: Mean geodesic angle per joint (22,), degrees; the root's after the heading.
    rot_deg: np.ndarray
    #: Mean root-relative position error per joint (22,), centimetres: both clips' rotations
    #: on one skeleton (the canonical one, :data:`COMMON_HEIGHT` tall).
    pos_cm: np.ndarray
    #: The same on each clip's own skeleton scaled to :data:`COMMON_HEIGHT`: adds the rigs'
    #: differences in proportions (where each places its hips, spine and shoulders).
    pos_own_cm: np.ndarray

    @property
    def rot_mean(self) -> float:
        return float(self.rot_deg.mean())

    @property
    def rot_worst(self) -> tuple[str, float]:
        j = int(np.argmax(self.rot_deg))
        return sk.JOINT_NAMES[j], float(self.rot_deg[j])

    @property
    def pos_mean(self) -> float:
        return float(self.pos_cm.mean())


def _relative(motion: Motion, own: bool = False, height: float = 1.0) -> np.ndarray:
    """Root-relative positions (F, 22, 3), metres: the clip's rotations on the canonical
    skeleton :data:`COMMON_HEIGHT` tall, or (``own``) on the clip's own skeleton, whose
    subject is ``height`` metres tall, scaled to that height."""
    if own:
        pos = motion.positions() * (COMMON_HEIGHT / height)
    else:
        scale = COMMON_HEIGHT / sk.Skeleton.canonical(1.0).height()
        pos = Motion(motion.local_rot, motion.root_pos, sk.Skeleton.canonical(scale)).positions()
    return pos - pos[:, :1]


def _signature(rel: np.ndarray) -> np.ndarray:
    """Heading-invariant pose signature (F, 44): joint heights and horizontal distances."""
    return np.concatenate([rel[..., 2], np.linalg.norm(rel[..., :2], axis=-1)], axis=-1)


def best_shift(sa: np.ndarray, sb: np.ndarray, max_shift: int) -> int:
    """Offset ``s`` minimising the mean squared difference of ``sa[t]`` and ``sb[t + s]``
    over their overlap (at least half the shorter signature)."""
    best, best_err = 0, np.inf
    least = max(1, min(len(sa), len(sb)) // 2)
    for s in range(-max_shift, max_shift + 1):
        a0, b0 = max(0, -s), max(0, s)
        n = min(len(sa) - a0, len(sb) - b0)
        if n < least:
            continue
        err = float(((sa[a0 : a0 + n] - sb[b0 : b0 + n]) ** 2).mean())
        if err < best_err:
            best, best_err = s, err
    return best


def _yaw(pa: np.ndarray, pb: np.ndarray) -> float:
    """Rotation about +Z (radians) that best maps horizontal points ``pa`` onto ``pb`` (2-D Procrustes)."""
    a, b = pa[..., :2].reshape(-1, 2), pb[..., :2].reshape(-1, 2)
    return float(np.arctan2((a[:, 0] * b[:, 1] - a[:, 1] * b[:, 0]).sum(), (a * b).sum()))


@dataclass
class AlignedPair:
    """Two copies of one take aligned in time and heading (:func:`align_clips`)."""

    #: Frames of ``b`` (at :data:`COMPARE_FPS`) that ``a`` starts later by.
    shift: int
    #: Rotation about +Z (radians) applied to ``a`` to face like ``b``.
    yaw: float
    #: Local rotations (n, 22, 4) over the overlap; ``a``'s root turned by ``yaw``.
    local_a: np.ndarray
    local_b: np.ndarray
    #: Root-relative positions (n, 22, 3), metres, on the canonical skeleton
    #: :data:`COMMON_HEIGHT` tall; ``a``'s turned by ``yaw``.
    rel_a: np.ndarray
    rel_b: np.ndarray
    #: The same on each clip's own skeleton scaled to :data:`COMMON_HEIGHT`.
    own_a: np.ndarray
    own_b: np.ndarray


def align_clips(a: Motion, b: Motion) -> AlignedPair:
    """Resample both clips to :data:`COMPARE_FPS`, find the time offset whose pose
    signatures agree best (within :data:`MAX_SHIFT_S`) and the heading (one rotation about
    +Z) that maps ``a``'s root-relative positions onto ``b``'s, and apply both to ``a``."""
    from engine.motion.retarget import resample_motion
    from engine.motion.retarget_measures import clip_height

    ha, hb = clip_height(a), clip_height(b)  # standing heights, as ``info`` prints them
    a, b = resample_motion(a, COMPARE_FPS), resample_motion(b, COMPARE_FPS)
    ra, rb = _relative(a), _relative(b)
    s = best_shift(_signature(ra), _signature(rb), int(MAX_SHIFT_S * COMPARE_FPS))
    a0, b0 = max(0, -s), max(0, s)
    n = min(len(a) - a0, len(b) - b0)
    cut = slice(a0, a0 + n), slice(b0, b0 + n)
    ra, rb = ra[cut[0]], rb[cut[1]]
    la, lb = a.local_rot[cut[0]].copy(), b.local_rot[cut[1]]
    yaw = _yaw(ra, rb)
    turn = np.array([np.cos(yaw / 2), 0.0, 0.0, np.sin(yaw / 2)])

    def turned(p: np.ndarray) -> np.ndarray:
        return Q.rotate(np.broadcast_to(turn, p.shape[:-1] + (4,)), p)

    la[:, 0] = Q.mul(np.broadcast_to(turn, la[:, 0].shape), la[:, 0])
    oa, ob = _relative(a, True, ha)[cut[0]], _relative(b, True, hb)[cut[1]]
    return AlignedPair(s, yaw, la, lb, turned(ra), rb, turned(oa), ob)


def compare_clips(a: Motion, b: Motion) -> ClipDifference:
    """Align ``a`` to ``b`` in time and heading (:func:`align_clips`) and measure their difference.

    Parameters
    ----------
    a, b : Motion
        Canonical clips of the same take (any frame rate; compared at :data:`COMPARE_FPS`).

    Returns
    -------
    ClipDifference
        The offset and heading found and the per-joint mean differences.
    """
    return difference(align_clips(a, b))


def difference(p: AlignedPair) -> ClipDifference:
    """The per-joint mean differences of an aligned pair (:func:`compare_clips` of its
    clips), for a caller that also needs the alignment (``offset_ablation(..., aligned=p)``)."""
    rot = np.degrees(Q.angle(p.local_a, p.local_b)).mean(0)
    pos = 100.0 * np.linalg.norm(p.rel_a - p.rel_b, axis=-1).mean(0)
    own = 100.0 * np.linalg.norm(p.own_a - p.own_b, axis=-1).mean(0)
    return ClipDifference(p.shift, float(np.degrees(p.yaw)), len(p.local_a), rot, pos, own)


def multi_rig_takes(mocap: str | Path) -> dict[str, list[str]]:
    """CMU takes on two or more rigs: ``cmu_trial`` -> paths relative to ``mocap``,
    from the shared data's ``manifest.json``."""
    mocap = Path(mocap)
    files = json.loads((mocap / "manifest.json").read_text())["files"]
    takes: dict[str, list[str]] = {}
    for entry in files:
        if entry.get("cmu_trial"):
            takes.setdefault(entry["cmu_trial"], []).append(entry["path"].removeprefix("mocap/"))
    return {t: sorted(p) for t, p in sorted(takes.items()) if len(p) > 1}
