"""Load any supported BVH rig onto the canonical skeleton.

How it works
------------
1. The source file is read and validated (:func:`engine.bvh.load_bvh`), its rig detected
   from its joint names (:func:`engine.rigs.detect_rig`).
2. Source FK gives world positions and rotations of every source joint, converted to the
   canonical axes (Z-up, facing -Y) and metres.
3. **Rest-pose alignment.** Rigs disagree on what zero rotation means (the iClone rig's
   zero pose points every bone upwards) and on how a joint's axes sit on its bone. For
   every canonical joint we build a *bone frame* from positions: its first axis along
   the bone, its second from a bone-rigid reference (the foot's forward direction for
   the legs, the eye line for the head, the index-pinky line for the hands, the elbow's
   hinge for the upper arm). The same rule applied to the canonical T-pose gives the
   canonical bone frame ``F_c``. The constant rotation ``A_j`` between a source joint's
   axes and its bone frame is estimated over the whole clip (a weighted quaternion
   mean, so frames where the reference is degenerate barely count), and the canonical
   world rotation is ``G_c(t) = G_s(t) A_j F_c^-1``. Positions follow the source's bone
   directions exactly; twist conventions become those of the canonical T-pose, so a
   T-pose in any rig is the canonical T-pose. Canonical joints a rig lacks (Daz has no
   toes or upper back) get identity local rotations.
4. Bone lengths are the canonical ones scaled by the ratio of leg lengths (the subject's
   size is kept, proportions are canonical); the root keeps the source trajectory.
5. The clip is re-floored (the 2nd-percentile lowest toe sits at the canonical toe height)
   and resampled to 60 fps (slerp for rotations, linear for the root).
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from engine import skeleton as sk
from engine.bvh import RawBVH, load_bvh
from engine.errors import UserError
from engine.kinematics import quaternion as Q
from engine.kinematics.fk import fk, local_from_global
from engine.motion import Motion
from engine.rigs import RigProfile, detect_rig

_AXIS = {"x": 0, "y": 1, "z": 2}

# Bone-frame rules: canonical joint -> (primary (from, [to candidates]), secondary spec).
# A secondary spec is ("vec", a, b) = b - a, or ("hinge", a, b, c) = (b - a) x (c - b).
_RULES: dict[str, tuple] = {
    "root": (("rhip", ["lhip"]), ("vec", "root", "lowerback")),
    "lowerback": (("lowerback", ["upperback", "chest", "lowerneck"]), ("vec", "rhip", "lhip")),
    "upperback": (("upperback", ["chest", "lowerneck"]), ("vec", "rshoulder", "lshoulder")),
    "chest": (("chest", ["lowerneck", "upperneck"]), ("vec", "rshoulder", "lshoulder")),
    "lowerneck": (("lowerneck", ["upperneck"]), ("vec", "r_eye", "l_eye")),
    "upperneck": (("r_eye", ["l_eye"]), ("vec", "upperneck", "eyes_mid")),
}
for _s in ("l", "r"):
    _RULES.update(
        {
            f"{_s}hip": ((f"{_s}hip", [f"{_s}knee"]), ("vec", f"{_s}ankle", f"{_s}_toe_tip")),
            f"{_s}knee": ((f"{_s}knee", [f"{_s}ankle"]), ("vec", f"{_s}ankle", f"{_s}_toe_tip")),
            f"{_s}ankle": ((f"{_s}ankle", [f"{_s}_toe_tip"]), ("vec", f"{_s}ankle", f"{_s}knee")),
            f"{_s}toe": ((f"{_s}toe", [f"{_s}_toe_tip"]), ("vec", f"{_s}ankle", f"{_s}knee")),
            f"{_s}clavicle": ((f"{_s}clavicle", [f"{_s}shoulder"]), ("vec", "chest", "lowerneck")),
            f"{_s}shoulder": (
                (f"{_s}shoulder", [f"{_s}elbow"]),
                ("hinge", f"{_s}shoulder", f"{_s}elbow", f"{_s}wrist"),
            ),
            f"{_s}elbow": ((f"{_s}elbow", [f"{_s}wrist"]), ("vec", f"{_s}_pinky", f"{_s}_index")),
            f"{_s}wrist": ((f"{_s}wrist", [f"{_s}_hand_mid"]), ("vec", f"{_s}_pinky", f"{_s}_index")),
        }
    )

#: Canonical landmark offsets (metres, canonical rest pose) from their anchor joints.
_CANON_LANDMARKS = {
    "l_toe_tip": ("ltoe", sk.END_SITES["ltoe"]),
    "r_toe_tip": ("rtoe", sk.END_SITES["rtoe"]),
    "l_eye": ("upperneck", np.array([0.032, -0.09, 0.07])),
    "r_eye": ("upperneck", np.array([-0.032, -0.09, 0.07])),
    "l_index": ("lwrist", np.array([0.09, -0.025, 0.0])),
    "l_pinky": ("lwrist", np.array([0.08, 0.03, 0.0])),
    "r_index": ("rwrist", np.array([-0.09, -0.025, 0.0])),
    "r_pinky": ("rwrist", np.array([-0.08, 0.03, 0.0])),
}
#: Elbow hinge axes in the canonical T-pose (the arm is straight there): elbows flex forward.
_CANON_HINGE = {"lshoulder": np.array([0.0, 0.0, -1.0]), "rshoulder": np.array([0.0, 0.0, 1.0])}
_TOE_HEIGHT = 0.045  # canonical toe joint height above the floor when standing (metres)


@dataclass
class RetargetReport:
    """What :func:`retarget` did, for ``info`` and the tests."""

    rig: str
    source_joints: int
    source_frames: int
    source_fps: float
    scale: float


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


def _frame(a: np.ndarray, b: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Rotation (as quaternion) whose x-axis is ``a`` and y-axis ``b`` made orthogonal.

    Returns the quaternions ``(..., 4)`` and a reliability weight ``(...,)`` (squared
    sine of the angle between a and b)."""
    an = a / np.maximum(np.linalg.norm(a, axis=-1, keepdims=True), 1e-9)
    bn = b / np.maximum(np.linalg.norm(b, axis=-1, keepdims=True), 1e-9)
    y = bn - (bn * an).sum(-1, keepdims=True) * an
    w = (y * y).sum(-1)
    y = y / np.maximum(np.linalg.norm(y, axis=-1, keepdims=True), 1e-9)
    z = np.cross(an, y)
    m = np.stack([an, y, z], axis=-1)
    return Q.normalize(Q.from_matrix(m)), w


def _mean_rotation(q: np.ndarray, w: np.ndarray) -> np.ndarray:
    """Weighted mean of rotations ``(F, 4)`` that cluster together (sign-aligned average)."""
    ref = q[np.argmax(w)]
    q = np.where(((q * ref).sum(-1) < 0)[:, None], -q, q)
    mean = (q * w[:, None]).sum(0)
    return Q.normalize(mean)


def _points(raw_pos: np.ndarray, raw: RawBVH, prof: RigProfile, world_rot: np.ndarray) -> dict[str, np.ndarray]:
    """Named source points (F, 3): mapped canonical joints and landmarks."""
    idx = {n: i for i, n in enumerate(raw.names)}
    pts = {c: raw_pos[:, idx[s]] for c, s in prof.joints.items()}
    for lm, spec in prof.landmarks.items():
        if spec.startswith("end:"):
            j = idx[spec[4:]]
            end = raw.end_sites.get(j)
            if end is None:
                raise UserError(f"{raw.path}: rig {prof.name}: joint {spec[4:]} has no end site")
            pts[lm] = raw_pos[:, j] + Q.rotate(world_rot[:, j], np.broadcast_to(end, raw_pos[:, j].shape))
        else:
            pts[lm] = raw_pos[:, idx[spec]]
    return pts


def _add_derived(pts: dict[str, np.ndarray]) -> None:
    if "l_eye" in pts and "r_eye" in pts:
        pts["eyes_mid"] = 0.5 * (pts["l_eye"] + pts["r_eye"])
    for s in ("l", "r"):
        if f"{s}_index" in pts and f"{s}_pinky" in pts:
            pts[f"{s}_hand_mid"] = 0.5 * (pts[f"{s}_index"] + pts[f"{s}_pinky"])


def _bone_frames(pts: dict[str, np.ndarray], hinge_default: dict[str, np.ndarray] | None = None):
    """Bone frame (quaternion, weight) per canonical joint whose rule resolves in ``pts``."""
    out = {}
    for joint, ((a0, a1s), sec) in _RULES.items():
        a1 = next((c for c in a1s if c in pts), None)
        if a0 not in pts or a1 is None:
            continue
        a = pts[a1] - pts[a0]
        if sec[0] == "vec":
            if sec[1] not in pts or sec[2] not in pts:
                continue
            b = pts[sec[2]] - pts[sec[1]]
        else:  # hinge
            if hinge_default is not None and joint in hinge_default:
                b = np.broadcast_to(hinge_default[joint], a.shape)
            elif all(k in pts for k in sec[1:]):
                b = np.cross(pts[sec[2]] - pts[sec[1]], pts[sec[3]] - pts[sec[2]])
            else:
                continue
        out[joint] = _frame(a, b)
    return out


def _canonical_frames() -> dict[str, np.ndarray]:
    rest = sk.Skeleton.canonical().rest_positions()
    pts = {n: rest[i][None] for i, n in enumerate(sk.JOINT_NAMES)}
    for lm, (anchor, off) in _CANON_LANDMARKS.items():
        pts[lm] = (rest[sk.JOINT_INDEX[anchor]] + off)[None]
    _add_derived(pts)
    return {j: q[0] for j, (q, _) in _bone_frames(pts, _CANON_HINGE).items()}


_CANON_FRAMES = _canonical_frames()


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


def retarget(raw: RawBVH, fps: float | None = None, profile: RigProfile | None = None) -> tuple[Motion, RetargetReport]:
    """Canonical :class:`Motion` (60 fps, Z-up metres, floor at 0) from a parsed BVH.

    Parameters
    ----------
    raw : RawBVH
        The parsed source file.
    fps : float, optional
        True frame rate of the source; default: from its ``Frame Time`` header.
    profile : RigProfile, optional
        Force a rig profile instead of detecting it from the joint names.
    """
    prof = profile or detect_rig(list(raw.names), raw.path)
    src_fps = float(fps) if fps else _snap_fps(raw.fps)
    if src_fps <= 0:
        raise UserError(f"{raw.path}: frame rate must be positive, got {src_fps}")
    skip = prof.skip_frames if raw.frames > prof.skip_frames + 2 else 0
    quats = raw.local_quaternions()[skip:]
    pos = raw.positions[skip:].copy()
    if prof.root_channels_relative_to_offset:
        pos[:, 0] += raw.offsets[0]
    offsets = raw.offsets
    parents = list(raw.parents)
    wpos, wrot = fk(quats, pos[:, 0], offsets, parents)

    basis = _basis_change(prof.up, prof.forward)
    cq = Q.from_matrix(basis)
    wpos = wpos @ basis.T * prof.units_to_m
    wrot = Q.mul(np.broadcast_to(cq, wrot.shape), wrot)

    idx = {n: i for i, n in enumerate(raw.names)}
    pts = _points(wpos, raw, prof, wrot)
    leg = np.linalg.norm(pts["lknee"][0] - pts["lhip"][0]) + np.linalg.norm(pts["lankle"][0] - pts["lknee"][0])
    canon_leg = np.linalg.norm(sk.REST_OFFSETS[[2, 3]], axis=-1).sum()
    scale = float(leg / canon_leg)

    n = wpos.shape[0]
    glob = np.zeros((n, sk.NUM_JOINTS, 4))
    if prof.align:
        _add_derived(pts)
        frames = _bone_frames(pts)
    for j, name in enumerate(sk.JOINT_NAMES):
        src = prof.joints.get(name)
        if src is None:
            glob[:, j] = glob[:, sk.PARENTS[j]]  # joint the rig lacks: identity local rotation
            continue
        g = wrot[:, idx[src]]
        if prof.align and name in frames:
            f, w = frames[name]
            a = _mean_rotation(Q.mul(Q.conjugate(g), f), w + 1e-6)
            g = Q.mul(g, np.broadcast_to(Q.mul(a, Q.conjugate(_CANON_FRAMES[name])), g.shape))
        elif prof.align:
            g = glob[:, sk.PARENTS[j]] if j else g
        glob[:, j] = g
    local = Q.unroll(Q.normalize(local_from_global(glob)), axis=0)
    root = pts["root"]

    local, root = _resample(local, root, src_fps)
    skel = sk.Skeleton.canonical(scale)
    motion = Motion(local, root, skel, sk.FPS, Path(raw.path).stem)
    _refloor(motion)
    return motion, RetargetReport(prof.name, len(raw.names), raw.frames, src_fps, scale)


def _snap_fps(fps: float) -> float:
    """Headers store a rounded frame time (0.008333 s); snap to the whole rate it means."""
    return float(round(fps)) if abs(fps - round(fps)) < 1e-3 * fps else fps


def _refloor(motion: Motion) -> None:
    """Shift the clip vertically so its feet stand on z = 0."""
    pos = motion.positions()
    toes = pos[:, [sk.JOINT_INDEX["ltoe"], sk.JOINT_INDEX["rtoe"]], 2].min(axis=1)
    ground = np.percentile(toes, 2.0)
    motion.root_pos[:, 2] += _TOE_HEIGHT * motion.skeleton.scale - ground


def manifest_fps(path: Path) -> float | None:
    """True frame rate of ``path`` from a ``manifest.json`` in one of its parent folders."""
    path = Path(path).resolve()
    for parent in list(path.parents)[:4]:
        man = parent / "manifest.json"
        if not man.is_file():
            continue
        try:
            data = json.loads(man.read_text())
        except (OSError, json.JSONDecodeError):
            return None
        rel = path.relative_to(parent).as_posix()
        for entry in data.get("files", []):
            listed = str(entry.get("path", ""))
            # paths are relative to the manifest's folder or to the data folder above it
            if (listed == rel or listed.endswith("/" + rel)) and entry.get("fps"):
                return float(entry["fps"])
    return None


def load_motion(path: str | Path, fps: float | None = None) -> Motion:
    """Load any supported BVH as a canonical motion (see module docs).

    ``fps`` overrides the file's header; otherwise a ``manifest.json`` beside the data
    (as in ``../shared/data/mocap``) gives the true rate, else the header does."""
    return load_with_report(path, fps)[0]


def load_with_report(path: str | Path, fps: float | None = None) -> tuple[Motion, RetargetReport]:
    raw = load_bvh(path)
    return retarget(raw, fps or manifest_fps(Path(path)))
