"""Acclaim ASF/AMC files (the CMU and HDM05 databases' own format) read as a BVH rig.

An ASF file holds a skeleton: one *bone* per line segment, each with a ``direction``
(unit vector, world axes of the rest pose), a ``length``, an ``axis`` (the bone's own
frame as three Euler angles and their order) and the ``dof`` that the AMC file animates.
An AMC file holds the motion: a frame number, then one line per moving bone with its dof
values in the order the ASF lists them. AMC has no frame rate; it comes from the data
manifest or ``--fps``.

:func:`load_amc` turns the pair into the same :class:`~engine.motion.bvh.RawBVH` that a
BVH file gives, with the joint names and hierarchy of the cgspeed BVH conversion of the
same skeleton (``Hips``, ``LHipJoint``, ``LeftUpLeg``...; see :data:`CGSPEED_NAMES`), so
the rest of the engine (rig detection, retargeting, write-back) treats it as that rig:

* each bone becomes a joint at the bone's start; its OFFSET is its parent bone's
  ``direction * length`` (the root's children sit on the root, and the children of
  :data:`CHILDREN_AT_START` on their parent's start, as cgspeed placed them), and a leaf
  bone's own segment becomes the end site;
* the joint's local rotation, in the world-aligned rest frames a BVH uses, is
  ``C M C^-1``: ``C`` is the bone's ``axis`` rotation and ``M`` the AMC dof rotation, each
  composed in its listed order with the first axis applied first;
* the root's position is the AMC ``TX TY TZ`` (absolute) plus the ASF root ``position``.

Every problem is an :class:`AsfAmcError` naming the file and line.
"""

from __future__ import annotations

import math
from collections.abc import Iterator
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from engine.errors import BVHError, UserError
from engine.kinematics import quaternion as Q
from engine.motion.bvh import RawBVH, file_error
from engine.validation import check_input_file

#: cgspeed BVH names of the CMU/Vicon ASF bones (the BVH conversion of the same skeletons
#: in ``cmu_mb/``); a bone missing here keeps its ASF name.
CGSPEED_NAMES = {
    "root": "Hips",
    "lhipjoint": "LHipJoint",
    "lfemur": "LeftUpLeg",
    "ltibia": "LeftLeg",
    "lfoot": "LeftFoot",
    "ltoes": "LeftToeBase",
    "rhipjoint": "RHipJoint",
    "rfemur": "RightUpLeg",
    "rtibia": "RightLeg",
    "rfoot": "RightFoot",
    "rtoes": "RightToeBase",
    "lowerback": "LowerBack",
    "upperback": "Spine",
    "thorax": "Spine1",
    "lowerneck": "Neck",
    "upperneck": "Neck1",
    "head": "Head",
    "lclavicle": "LeftShoulder",
    "lhumerus": "LeftArm",
    "lradius": "LeftForeArm",
    "lwrist": "LeftHand",
    "lhand": "LeftFingerBase",
    "lfingers": "LeftHandIndex1",
    "lthumb": "LThumb",
    "rclavicle": "RightShoulder",
    "rhumerus": "RightArm",
    "rradius": "RightForeArm",
    "rwrist": "RightHand",
    "rhand": "RightFingerBase",
    "rfingers": "RightHandIndex1",
    "rthumb": "RThumb",
}
#: Bones whose children the cgspeed conversion attaches at the bone's start rather than its
#: end (neck and clavicles on the thorax's start, hand and thumb on the wrist's). Most of
#: the BVH training data is that conversion; placing these joints as it does keeps one
#: rig's proportions whatever the file format (``cmu_asf/02`` matches ``cmu_mb/02_*``).
CHILDREN_AT_START = frozenset({"thorax", "lwrist", "rwrist"})
#: Largest accepted ``|value|`` of a direction, length, position or dof value.
MAX_VALUE = 1e6
_AXES = "xyz"
_ROT_ORDER = ("z", "y", "x")  # Euler order of the RawBVH rotations (cgspeed's channel order)


class AsfAmcError(BVHError):
    """An ASF or AMC file that cannot be read. ``str()`` reads ``file:line: message``."""


@dataclass
class Bone:
    """One ASF bone: its segment (file units), frame and animated dof."""

    name: str
    direction: np.ndarray = field(default_factory=lambda: np.zeros(3))
    length: float = 0.0
    axis_deg: np.ndarray = field(default_factory=lambda: np.zeros(3))
    axis_order: str = "xyz"
    dof: tuple[str, ...] = ()
    line: int = 0


@dataclass
class Skeleton:
    """An ASF skeleton: bones in depth-first order (the root first) and their parents."""

    path: str
    bones: list[Bone]
    parents: list[int]
    root_order: tuple[str, ...]
    radians: bool
    length_unit: float

    def index(self) -> dict[str, int]:
        return {b.name: i for i, b in enumerate(self.bones)}


def _lines(path: str, kind: str) -> Iterator[tuple[int, list[str]]]:
    """(line number, tokens) of every non-blank line without its ``#`` comment. Bytes that
    are not UTF-8 (Latin-1 paths in HDM05 comments) are replaced, never fatal."""
    try:
        check_input_file(path, kind)
        with open(path, encoding="utf-8", errors="replace") as fh:
            for n, text in enumerate(fh, 1):
                tokens = text.split("#", 1)[0].split()
                if tokens:
                    yield n, tokens
    except AsfAmcError:
        raise
    except (UserError, OSError) as exc:
        raise file_error(path, exc, AsfAmcError, kind) from None


def _number(path: str, line: int, token: str, what: str) -> float:
    try:
        value = float(token)
    except ValueError:
        raise AsfAmcError(path, f"{what}: expected a number, got {token[:40]!r}", line) from None
    if not math.isfinite(value) or abs(value) > MAX_VALUE:
        raise AsfAmcError(path, f"{what}: {token[:40]} is not a finite number below {MAX_VALUE:g}", line)
    return value


def _vector(path: str, line: int, tokens: list[str], what: str) -> np.ndarray:
    if len(tokens) < 3:
        raise AsfAmcError(path, f"{what}: expected 3 numbers, got {len(tokens)}", line)
    return np.array([_number(path, line, t, what) for t in tokens[:3]])


def _order(path: str, line: int, token: str, what: str) -> str:
    order = token.lower()
    if len(order) != 3 or sorted(order) != ["x", "y", "z"]:
        raise AsfAmcError(path, f"{what}: expected an axis order such as XYZ, got {token[:40]!r}", line)
    return order


def load_asf(path: str | Path) -> Skeleton:
    """Read and validate an ASF skeleton (see the module docs)."""
    path = str(path)
    section = ""
    bones: dict[str, Bone] = {}
    children: dict[str, list[str]] = {}
    root_order: tuple[str, ...] = ("tx", "ty", "tz", "rx", "ry", "rz")
    root = Bone("root")
    radians, unit = False, 1.0
    bone: Bone | None = None
    in_hierarchy = False
    for n, tok in _lines(path, "ASF file"):
        key = tok[0].lower()
        if key.startswith(":"):
            section = key
            if section == ":units" and len(tok) > 1:  # a one-line units section
                tok = tok[1:]
                key = tok[0].lower()
            else:
                continue
        if section == ":units":
            if key == "angle" and len(tok) > 1:
                if tok[1].lower() not in ("deg", "rad"):
                    raise AsfAmcError(path, f"angle unit must be deg or rad, got {tok[1][:40]!r}", n)
                radians = tok[1].lower() == "rad"
            elif key == "length" and len(tok) > 1:
                unit = _number(path, n, tok[1], "length unit")
        elif section == ":root":
            if key == "order":
                root_order = tuple(t.lower() for t in tok[1:])
                bad = [t for t in root_order if t not in ("tx", "ty", "tz", "rx", "ry", "rz")]
                if bad or len(set(root_order)) != len(root_order):
                    raise AsfAmcError(
                        path, f"root order: expected TX TY TZ RX RY RZ in some order, got {' '.join(tok[1:])[:80]!r}", n
                    )
            elif key == "axis" and len(tok) > 1:
                root.axis_order = _order(path, n, tok[1], "root axis")
            elif key == "position":
                root.direction = _vector(path, n, tok[1:], "root position")
            elif key == "orientation":
                root.axis_deg = _vector(path, n, tok[1:], "root orientation")
        elif section == ":bonedata":
            if key == "begin":
                if bone is not None:
                    raise AsfAmcError(path, f"'begin' inside bone {bone.name!r} (missing 'end')", n)
                bone = Bone("", line=n)
            elif bone is None:
                raise AsfAmcError(path, f"{tok[0][:40]!r} outside a begin ... end bone block", n)
            elif key == "end":
                if not bone.name:
                    raise AsfAmcError(path, "bone without a name", bone.line)
                if bone.name in bones or bone.name == "root":
                    raise AsfAmcError(path, f"bone {bone.name!r} is defined twice", bone.line)
                bones[bone.name] = bone
                bone = None
            elif key == "name" and len(tok) > 1:
                bone.name = tok[1]
            elif key == "direction":
                bone.direction = _vector(path, n, tok[1:], f"bone {bone.name!r} direction")
            elif key == "length" and len(tok) > 1:
                bone.length = _number(path, n, tok[1], f"bone {bone.name!r} length")
            elif key == "axis":
                bone.axis_deg = _vector(path, n, tok[1:], f"bone {bone.name!r} axis")
                bone.axis_order = _order(path, n, tok[4] if len(tok) > 4 else "xyz", f"bone {bone.name!r} axis")
            elif key == "dof":
                dof = tuple(t.lower() for t in tok[1:])
                bad = [t for t in dof if t not in ("rx", "ry", "rz")]
                if bad or len(set(dof)) != len(dof):
                    raise AsfAmcError(
                        path,
                        f"bone {bone.name!r} dof: expected rx, ry, rz (each once), got {' '.join(tok[1:])[:80]!r}",
                        n,
                    )
                bone.dof = dof
        elif section == ":hierarchy":
            if key == "begin":
                in_hierarchy = True
            elif key == "end":
                in_hierarchy = False
            elif in_hierarchy:
                parent, kids = tok[0], tok[1:]
                for kid in kids:
                    children.setdefault(parent, []).append(kid)
                    for name in (parent, kid):
                        if name != "root" and name not in bones:
                            raise AsfAmcError(path, f"hierarchy names bone {name[:40]!r}, which :bonedata lacks", n)
    if bone is not None:
        raise AsfAmcError(path, f"bone {bone.name or '(unnamed)'!r} has no 'end'", bone.line)
    if not bones:
        raise AsfAmcError(path, "no :bonedata bones; is this an ASF skeleton file?")
    if "root" not in children:
        raise AsfAmcError(path, "the :hierarchy section attaches no bone to the root")
    order: list[Bone] = [root]
    parents = [-1]
    stack = [(kid, 0) for kid in reversed(children["root"])]
    seen = {"root"}
    while stack:
        name, parent_at = stack.pop()
        if name in seen:
            raise AsfAmcError(path, f"bone {name[:40]!r} appears twice in the :hierarchy (a loop or two parents)")
        seen.add(name)
        order.append(bones[name])
        parents.append(parent_at)
        me = len(order) - 1
        stack.extend((kid, me) for kid in reversed(children.get(name, [])))
    return Skeleton(path, order, parents, root_order, radians, unit)


def _rotation(angles: np.ndarray, order: str) -> np.ndarray:
    """Quaternions (..., 4) of Euler ``angles`` (..., 3) in radians about fixed axes, the
    first axis of ``order`` applied first (``xyz``: ``Rz Ry Rx``)."""
    q = Q.identity(angles.shape[:-1])
    for k, a in enumerate(order):
        axis = np.zeros(3)
        axis[_AXES.index(a)] = 1.0
        q = Q.mul(Q.from_axis_angle(np.broadcast_to(axis, angles.shape[:-1] + (3,)), angles[..., k]), q)
    return q


def _read_amc(path: str, skel: Skeleton, max_frames: int | None) -> tuple[np.ndarray, int]:
    """AMC values as an array (F, V): per frame, the bones' dof values in skeleton order
    (root first, its ``order``); and the number of frames in the file."""
    index = skel.index()
    dofs = [skel.root_order] + [b.dof for b in skel.bones[1:]]
    starts = np.cumsum([0] + [len(d) for d in dofs])
    rows: list[np.ndarray] = []
    row: np.ndarray | None = None
    seen: set[str] = set()
    frame_line = first = frames = 0

    def close() -> None:
        if row is None:
            return
        missing = [skel.bones[i].name for i in range(len(dofs)) if dofs[i] and skel.bones[i].name not in seen]
        if missing:
            raise AsfAmcError(path, f"frame {frames} lacks bone {missing[0]!r}", frame_line)
        if max_frames is None or len(rows) < max_frames:
            rows.append(row)

    for n, tok in _lines(path, "AMC file"):
        if tok[0].startswith(":"):
            if frames:
                raise AsfAmcError(path, f"keyword {tok[0][:40]!r} after the first frame", n)
            if tok[0].upper() == ":RADIANS" and not skel.radians:
                raise AsfAmcError(path, f":RADIANS, but the skeleton {skel.path} gives angles in degrees", n)
            continue
        if len(tok) == 1 and tok[0].isdigit():
            close()
            number = int(tok[0])
            if frames == 0:
                if number not in (0, 1):
                    raise AsfAmcError(path, f"first frame number {tok[0][:20]}: expected 0 or 1", n)
                first = number
            elif number != first + frames:
                raise AsfAmcError(path, f"frame number {tok[0][:20]}: expected {first + frames}", n)
            frames += 1
            row, seen, frame_line = np.zeros(int(starts[-1])), set(), n
            continue
        if row is None:
            raise AsfAmcError(path, f"{tok[0][:40]!r} before the first frame number", n)
        name = tok[0]
        if name not in index:
            raise AsfAmcError(path, f"bone {name[:40]!r} is not in the skeleton {skel.path}", n)
        if name in seen:
            raise AsfAmcError(path, f"bone {name!r} twice in frame {frames}", n)
        i = index[name]
        want = len(dofs[i])
        if len(tok) - 1 != want:
            raise AsfAmcError(path, f"bone {name!r}: expected {want} values (its dof), got {len(tok) - 1}", n)
        seen.add(name)
        row[starts[i] : starts[i + 1]] = [_number(path, n, t, f"bone {name!r}") for t in tok[1:]]
    close()
    if not rows:
        raise AsfAmcError(path, "no frames; is this an AMC motion file?")
    return np.stack(rows), frames


def load_amc(path: str | Path, skeleton: str | Path, max_frames: int | None = None, fps: float = 120.0) -> RawBVH:
    """Read an AMC motion with its ASF skeleton as a :class:`RawBVH` on the cgspeed BVH rig
    of the same skeleton (see the module docs).

    Parameters
    ----------
    path : str or Path
        The AMC file.
    skeleton : str or Path
        Its ASF file.
    max_frames : int, optional
        Keep only the first frames (every line is still checked).
    fps : float
        Frame rate written into the result's ``frame_time`` (AMC has none; callers pass
        the manifest's or ``--fps``; retargeting takes the true rate separately too).
    """
    path = str(path)
    skel = load_asf(skeleton)
    values, total = _read_amc(path, skel, max_frames)
    f, j = values.shape[0], len(skel.bones)
    to_rad = 1.0 if skel.radians else math.pi / 180.0
    offsets = np.zeros((j, 3))
    for i in range(1, j):
        p = skel.parents[i]
        if p > 0 and skel.bones[p].name not in CHILDREN_AT_START:
            offsets[i] = skel.bones[p].direction * skel.bones[p].length
    end_sites = {i: b.direction * b.length for i, b in enumerate(skel.bones) if i > 0 and i not in skel.parents}
    positions = np.repeat(offsets[None], f, axis=0)
    local = np.empty((f, j, 4))
    col = 0
    for i, b in enumerate(skel.bones):
        dof = skel.root_order if i == 0 else b.dof
        vals = values[:, col : col + len(dof)]
        col += len(dof)
        angles = np.zeros((f, 3))
        rot_axes = ""
        for k, d in enumerate(dof):
            if d[0] == "t":
                positions[:, 0, _AXES.index(d[1])] = vals[:, k] + skel.bones[0].direction[_AXES.index(d[1])]
            else:
                angles[:, len(rot_axes)] = vals[:, k] * to_rad
                rot_axes += d[1]
        m = _rotation(angles[:, : len(rot_axes)], rot_axes) if rot_axes else Q.identity((f,))
        c = _rotation(np.radians(b.axis_deg) if not skel.radians else b.axis_deg, b.axis_order)
        local[:, i] = Q.mul(Q.mul(np.broadcast_to(c, (f, 4)), m), np.broadcast_to(Q.conjugate(c), (f, 4)))
    order = np.array([list(_ROT_ORDER)] * j)
    euler = np.degrees(Q.to_euler(Q.normalize(local), np.broadcast_to(order, (f, j, 3))))
    euler = (euler + 180.0) % 360.0 - 180.0
    names = tuple(CGSPEED_NAMES.get(b.name, b.name) for b in skel.bones)
    rot_channels = tuple(f"{a.upper()}rotation" for a in _ROT_ORDER)
    channels = (("Xposition", "Yposition", "Zposition", *rot_channels),) + (rot_channels,) * (j - 1)
    return RawBVH(
        names=names,
        parents=tuple(skel.parents),
        offsets=offsets,
        end_sites=end_sites,
        channels=channels,
        rot_order=order,
        positions=positions,
        rotations_deg=euler,
        frame_time=1.0 / fps,
        path=path,
        file_frames=total,
    )
