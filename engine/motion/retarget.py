"""Load any humanoid BVH rig onto the canonical skeleton, keeping the subject's proportions.

How it works (details and figures in ``docs/skeleton.md``)
----------------------------------------------------------
1. The source file is read and validated (:func:`engine.motion.bvh.load_bvh`); its rig comes from
   a mapping file, a TOML profile or the automatic mapping (:func:`engine.motion.rigs.resolve_rig`).
2. Source FK gives world positions and rotations of every source joint, converted to the
   canonical axes (Z-up, facing -Y) and metres.
3. **Rotations defined by the body.** Limbs, hands, feet, neck and head get the rotation
   of a bone frame built each frame from the body's positions (:mod:`engine.motion.retarget_body`:
   swing from the bone, twist from the bending plane, the knuckles, the foot, the eyes),
   so the source rig's joint axes do not matter. The torso, and any joint whose defining
   points the rig lacks, keep the source joint's rotation times one constant ``R``
   (``G_c = G_s R``, :mod:`engine.motion.retarget_frames`). Canonical joints a rig lacks get
   identity local rotations.
4. **True proportions.** Bone offsets are measured per clip along the source chain
   (:func:`~engine.motion.retarget_measures.measure_offsets`), so mapped joints land where
   the source's are and the clip's height is the subject's
   (:func:`~engine.motion.retarget_measures.standing_height`); the root keeps the source trajectory.
5. The clip is resampled to 60 fps (slerp for rotations, linear for the root) and
   re-floored (the 2nd-percentile lowest toe sits at the canonical toe height).

Which of these choices apply (body-defined twist, straightened elbows and knees, where the
toe tip lies) is the :class:`RetargetStrategy` given (:mod:`engine.motion.retarget_strategy`).
The :class:`RetargetReport` keeps what is needed to go back onto the source rig
(:mod:`engine.motion.write_back`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from engine import skeleton as sk
from engine.errors import UserError
from engine.kinematics import quaternion as Q
from engine.kinematics.fk import fk, local_from_global
from engine.motion import retarget_body as RB
from engine.motion import retarget_frames as RF
from engine.motion.bvh import RawBVH
from engine.motion.clip import Motion
from engine.motion.retarget_inputs import (  # noqa: F401 - re-exported: callers import them from here
    MODELS_DATA,
    manifest_entry,
    manifest_fps,
    models_strategy,
    rest_frame_count,
    snap_fps,
)
from engine.motion.retarget_measures import clip_height, measure_offsets, refloor, standing_height, toe_tips
from engine.motion.retarget_rotations import rigid_hands, straightened_offsets, tip_points, world_rotations
from engine.motion.retarget_strategy import CURRENT, RETARGET_VERSION, STRATEGIES, RetargetStrategy  # noqa: F401 - re-exported: callers import them from here
from engine.motion.rigs import RigProfile, resolve_rig
from engine.motion.source_file import load_source
from engine.validation import SKELETON, check_value

_AXIS = {"x": 0, "y": 1, "z": 2}
#: Source frames kept at least when only the start of a clip is loaded (the rest-pose
#: alignment and the heights are measured on them; every shared clip is shorter).
ALIGN_FRAMES = 8192
#: Highest source frame rate accepted (engine.validation.BVH_HEADER / MANIFEST / --fps).
MAX_SOURCE_FPS = 1000
_LEG = [sk.JOINT_INDEX[n] for n in ("lknee", "lankle")]


@dataclass
class RetargetReport:
    """What :func:`retarget` did: for ``info``, the tests and writing back onto the source rig.

    ``align`` holds, per canonical joint, the constant rotation ``R`` with
    ``G_canonical = G_source R`` (None for joints the rig lacks); ``basis`` the matrix
    taking source axes to canonical ones; ``floor_shift`` the height (metres) added to
    the root when re-flooring."""

    rig: str
    source_joints: int
    source_frames: int
    source_fps: float
    scale: float
    profile: RigProfile | None = None
    align: list | None = None
    basis: np.ndarray | None = None
    floor_shift: float = 0.0
    skip: int = 0
    source_height_m: float = float("nan")
    height_m: float = float("nan")
    #: The source's toe tips as offsets (metres) in the canonical toe frames, by toe name.
    toe_tips: dict | None = None
    #: Canonical (60 fps) frames of the whole file, even when only its start was loaded.
    frames: int = 0
    #: Retargeting definition used.
    strategy: RetargetStrategy = CURRENT
    #: Joints whose rotation the body defines; the other mapped joints keep the source's.
    body_joints: list | None = None
    #: Body-defined joints whose defining points a documented rule stood in for: joint -> rule.
    twist_rules: dict | None = None

    @property
    def version(self) -> int:
        """The number of :attr:`strategy` (``info`` prints it as ``retarget_version``)."""
        return self.strategy.version

    @property
    def copied(self) -> bool:
        """Whether the rotations were copied as they are (``align = false``: the canonical
        rig, whose rotations are canonical by definition) rather than retargeted."""
        return self.profile is not None and not self.profile.align

    @property
    def source_twist_joints(self) -> list[str]:
        """Mapped joints of :data:`engine.motion.retarget_body.BODY_JOINTS` whose defining points
        the rig lacks: they keep the source's rotation (one constant alignment). None on a
        rig whose rotations are copied (:attr:`copied`): nothing there is retargeted."""
        if self.profile is None or self.body_joints is None or self.copied:
            return []
        return [j for j in RB.BODY_JOINTS if j in self.profile.joints and j not in self.body_joints]

    @property
    def mapping(self) -> dict[str, str]:
        """Canonical joint -> source joint."""
        return dict(self.profile.joints) if self.profile else {}


def _basis_change(up: str, forward: str) -> np.ndarray:
    """Rotation matrix taking source axes to canonical ones (up -> +Z, forward -> -Y)."""

    def vec(a: str) -> np.ndarray:
        v = np.zeros(3)
        v[_AXIS[a[1]]] = 1.0 if a[0] == "+" else -1.0
        return v

    u, f = vec(up), vec(forward)
    left = np.cross(u, f)
    src = np.stack([left, -f, u], axis=1)  # columns: source vectors mapped to X, Y, Z
    return src.T  # orthonormal: inverse = transpose


def _points(
    raw_pos: np.ndarray, raw: RawBVH, prof: RigProfile, world_rot: np.ndarray, end_sites: dict
) -> dict[str, np.ndarray]:
    """Named source points (F, 3): mapped canonical joints and landmarks (``end_sites``:
    the source's end-site offsets by joint index)."""
    idx = {n: i for i, n in enumerate(raw.names)}
    pts = {c: raw_pos[:, idx[s]] for c, s in prof.joints.items()}
    for lm, spec in prof.landmarks.items():
        if spec.startswith("end:"):
            j = idx.get(spec[4:])
            end = end_sites.get(j) if j is not None else None
            if end is None:
                raise UserError(f"{raw.path}: rig {prof.name}: joint {spec[4:]} has no end site")
            pts[lm] = raw_pos[:, j] + Q.rotate(
                world_rot[:, j], np.broadcast_to(end * prof.units_to_m, raw_pos[:, j].shape)
            )
        elif spec in idx:
            pts[lm] = raw_pos[:, idx[spec]]
        else:
            raise UserError(f"{raw.path}: rig {prof.name}: landmark {lm} names a joint not in the file: {spec}")
    return pts


def _resampled_count(n: int, fps: float, target: float = sk.FPS) -> int:
    """Frames :func:`_resample` makes of ``n`` frames at ``fps``."""
    if abs(fps - target) < 1e-6 or n < 2:
        return n
    return int(np.floor((n - 1) / fps * target + 1e-9)) + 1


def _resample(local_rot: np.ndarray, root: np.ndarray, fps: float, target: float = sk.FPS):
    n = local_rot.shape[0]
    if abs(fps - target) < 1e-6 or n < 2:
        return local_rot, root
    duration = (n - 1) / fps
    t = np.arange(int(np.floor(duration * target + 1e-9)) + 1) / target * fps
    i0 = np.minimum(np.floor(t).astype(int), n - 1)
    i1 = np.minimum(i0 + 1, n - 1)
    a = (t - i0)[:, None]
    root_out = root[i0] * (1 - a) + root[i1] * a
    q0, q1 = local_rot[i0], local_rot[i1]
    q1 = np.where(((q0 * q1).sum(-1) < 0)[..., None], -q1, q1)
    rot_out = Q.slerp(q0, q1, np.broadcast_to(a[:, None], q0.shape[:-1] + (1,)))
    return Q.normalize(rot_out), root_out


def retarget(
    raw: RawBVH,
    fps: float | None = None,
    profile: RigProfile | None = None,
    rig_map: str | Path | None = None,
    strategy: RetargetStrategy | None = None,
) -> tuple[Motion, RetargetReport]:
    """Canonical :class:`Motion` (60 fps, Z-up metres, floor at 0) from a parsed BVH.

    Parameters
    ----------
    raw : RawBVH
        The parsed source file.
    fps : float, optional
        True frame rate of the source; default: from its ``Frame Time`` header.
    profile : RigProfile, optional
        Force a rig profile instead of detecting it from the joint names.
    rig_map : path, optional
        A mapping file (``rig suggest`` writes one) that overrides detection.
    strategy : RetargetStrategy, optional
        Retargeting definition; default: the one the shipped models learnt from
        (:func:`models_strategy`), so that what feeds them looks like what they learnt.
        ``convert``, ``info`` and ``data prepare`` ask for :data:`CURRENT`.
    """
    strategy = models_strategy() if strategy is None else strategy
    prof = profile or resolve_rig(raw, rig_map)
    src_fps = float(fps) if fps else snap_fps(raw.fps)
    if src_fps <= 0:
        raise UserError(f"{raw.path}: frame rate must be positive, got {src_fps}")
    skip = prof.skip_frames or rest_frame_count(raw)
    skip = skip if raw.total_frames > skip + 2 else 0
    canonical = _resampled_count(raw.total_frames - skip, src_fps)
    check_value(SKELETON["canonical frames"], canonical, f"{raw.path}: at {src_fps:g} frames/s", "frames at 60 fps")
    quats = raw.local_quaternions()[skip:]
    pos = raw.positions[skip:].copy()
    if prof.root_channels_relative_to_offset:
        pos[:, 0] += raw.offsets[0]
    _check_root(raw.path, pos[:, 0], prof.units_to_m)
    offsets, ends = straightened_offsets(
        raw,
        prof,
        elbows=prof.straight_elbows and strategy.straight_elbows,
        knees=prof.straight_knees and strategy.straight_knees,
    )
    moving = [k for k, c in enumerate(raw.channels) if k > 0 and len(c) == 6]
    if moving:  # position channels below the root (a 6-channel Hips under a static ROOT) move their joint
        offsets = np.repeat(offsets[None], len(pos), axis=0)
        offsets[:, moving] = pos[:, moving]
    wpos, wrot = fk(quats, pos[:, 0], offsets, list(raw.parents))

    basis = _basis_change(prof.up, prof.forward)
    cq = Q.from_matrix(basis)
    wpos = wpos @ basis.T * prof.units_to_m
    wrot = Q.mul(np.broadcast_to(cq, wrot.shape), wrot)

    idx = {n: i for i, n in enumerate(raw.names)}
    pts = _points(wpos, raw, prof, wrot, ends)
    RF.add_derived(pts)
    leg = sum(
        float(np.median(np.linalg.norm(pts[b] - pts[a], axis=-1))) for a, b in (("lhip", "lknee"), ("lknee", "lankle"))
    )
    leg_scale = leg / float(np.linalg.norm(sk.REST_OFFSETS[_LEG], axis=-1).sum())
    _check_height(raw.path, leg_scale)

    hands = rigid_hands(raw, prof)
    pts.update(tip_points(raw, prof, wpos, wrot, ends, hands))
    glob, align, body_joints, rules = world_rotations(prof, pts, wrot, idx, cq, strategy, hands)
    joint_pts = {n: pts[n] for n in [*sk.JOINT_NAMES, "l_toe_tip", "r_toe_tip"] if n in pts}
    skel = sk.Skeleton(offsets=measure_offsets(joint_pts, glob, leg_scale))
    local = Q.unroll(Q.normalize(local_from_global(glob)), axis=0)
    root = pts["root"]
    feet = [pts[k][:, 2] for k in ("lankle", "rankle", "ltoe", "rtoe", "l_toe_tip", "r_toe_tip") if k in pts]
    src_height = standing_height(pts["upperneck"][:, 2], np.min(feet, axis=0), skel)
    tips = toe_tips(pts, local, root, skel)

    local, root = _resample(local, root, src_fps)
    motion = Motion(local, root, skel, sk.FPS, Path(raw.path).stem)
    shift = refloor(motion)
    report = RetargetReport(
        prof.name,
        len(raw.names),
        raw.total_frames,
        src_fps,
        skel.scale,
        prof,
        align,
        basis,
        shift,
        skip,
        src_height,
        clip_height(motion, tips),
        tips,
        canonical,
        strategy,
        body_joints,
        rules,
    )
    return motion, report


def resample_motion(motion: Motion, fps: float) -> Motion:
    """The same motion at another frame rate (slerp for rotations, linear for the root)."""
    rot, root = _resample(motion.local_rot, motion.root_pos, motion.fps, fps)
    return Motion(rot, root, motion.skeleton, float(fps), motion.name)


def _check_height(path: str, scale: float) -> None:
    """Refuse a subject no motion comes from (:data:`engine.validation.SKELETON`): a
    standing height outside 0.5-3 m (all-zero or kilometre OFFSETs, a wrong unit)."""
    height = sk.Skeleton.canonical(1.0).height() * scale if np.isfinite(scale) else scale
    check_value(SKELETON["height"], round(height, 3), f"{path}: skeleton", "height")


def _check_root(path: str, root: np.ndarray, units_to_m: float) -> None:
    """Refuse root positions (file units) beyond +-10 km, which no solver can use."""
    with np.errstate(over="ignore", invalid="ignore"):
        worst = float(np.abs(root).max()) * units_to_m if root.size else 0.0
    check_value(SKELETON["root position"], worst, f"{path}: motion", "largest root coordinate")


def load_motion(
    path: str | Path,
    fps: float | None = None,
    rig_map: str | Path | None = None,
    max_frames: int | None = None,
    strategy: RetargetStrategy | None = None,
    asf: str | Path | None = None,
) -> Motion:
    """Load any humanoid BVH, or AMC with its ASF skeleton (``asf``, else found beside it;
    :mod:`engine.motion.source_file`), as a canonical motion (see module docs).

    ``fps`` overrides the file's header; otherwise a ``manifest.json`` beside the data
    (as in ``../shared/data/mocap``) gives the true rate, else the header does.
    ``rig_map`` is a mapping file that overrides rig detection. ``max_frames``
    (canonical frames) reads only the start of a long file; see :func:`load_with_report`.
    ``strategy`` is the retargeting definition (default: the shipped models', see
    :func:`retarget`)."""
    motion = load_with_report(path, fps, rig_map, max_frames, strategy, asf)[0]
    return motion.slice(0, max_frames) if max_frames else motion


def source_frames_needed(max_frames: int | None) -> int | None:
    """Source frames to keep for ``max_frames`` canonical frames at any accepted source
    rate (None: all), at least :data:`ALIGN_FRAMES`."""
    if max_frames is None:
        return None
    return max(ALIGN_FRAMES, math.ceil(max_frames * MAX_SOURCE_FPS / sk.FPS) + 64)


def load_with_report(
    path: str | Path,
    fps: float | None = None,
    rig_map: str | Path | None = None,
    max_frames: int | None = None,
    strategy: RetargetStrategy | None = None,
    asf: str | Path | None = None,
) -> tuple[Motion, RetargetReport]:
    """:func:`load_motion` plus the :class:`RetargetReport`. With ``max_frames``, only the
    source frames those canonical frames need are kept (at least :data:`ALIGN_FRAMES`,
    which the rest-pose alignment averages over); every row is still checked, and the
    report's ``source_frames`` / ``frames`` describe the whole file."""
    raw = load_source(path, source_frames_needed(max_frames), asf, fps)
    return retarget(raw, fps or manifest_fps(Path(path)), rig_map=rig_map, strategy=strategy)
