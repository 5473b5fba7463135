"""Synthetic BVH files on the rigs of the common naming families.

Joint names and hierarchies are those of the real rigs (facts from their public BVH
headers). OFFSETs, family by family:

* real, from public headers (:mod:`rig_headers`, each with its source): ``cmu`` (the CMU
  conversion rig, in CMU's ASF unit of 1/0.45 inch), ``mixamo`` (a Mixamo export,
  ``mixamorig7:`` prefix), ``daz`` (the cgspeed "Daz-friendly" rig, with its eyes and
  fingers), ``lafan`` (LAFAN1) and ``joint_root`` (the Bandai Namco dataset's rig), the
  last two with bone frames along x, so their zero pose is not a T-pose;
* synthetic: ``smpl``, ``iclone``, ``unreal``, ``rokoko``, ``xsens`` are adult proportions
  (:data:`_BONES`, metres) written in each family's unit and up axis. No public header
  with numbers for these rigs was found in the indexed sources (SMPL's offsets come from
  the licensed model files; the others' exports are not published as text); the names
  and hierarchies are still theirs.

The motion is a synthetic walk from the rig's T-pose: hips swing and knees bend about
the lateral axis, elbows about the vertical one, the spine sways, the root walks
forward and turns. On a rig whose zero pose is not a T-pose (LAFAN1, Bandai), each joint's
rotation carries the bone frame that makes the T-pose (:func:`rig_headers.tpose_frames`),
as the real files' rotations do.
"""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np

from . import rig_headers

# Adult proportions, Y-up, facing +Z, metres (T-pose): bone -> offset from its parent.
_BONES = {
    "hipL": (0.09, -0.07, 0.0),
    "knee": (0.0, -0.43, 0.0),
    "ankle": (0.0, -0.42, 0.0),
    "toe": (0.0, -0.07, 0.13),
    "toe_end": (0.0, 0.0, 0.06),
    "spine": (0.0, 0.11, -0.01),
    "neck": (0.0, 0.16, 0.0),
    "head": (0.0, 0.10, 0.02),
    "head_end": (0.0, 0.18, 0.0),
    "clav": (0.04, 0.11, 0.0),
    "clav_side": (0.16, 0.0, 0.0),
    "upper": (0.28, 0.0, 0.0),
    "fore": (0.26, 0.0, 0.0),
    "hand_end": (0.09, 0.0, 0.0),
}
_CMU = "cmu_asf"


def _o(key: str, side: str = "L", scale: float = 1.0) -> tuple[float, float, float]:
    x, y, z = _BONES[key]
    return ((x if side == "L" else -x) * scale, y * scale, z * scale)


def _humanoid(n: dict, spine: list[tuple[str, tuple]], scale: float, clav: bool = True, root_name=None):
    """Generic hierarchy from a name table: (name, parent, offset) rows and end sites."""
    rows = [(n["root"], None, (0.0, 0.0, 0.0))]
    parent = n["root"]
    for name, off in spine:
        rows.append((name, parent, off))
        parent = name
    chest = parent
    rows += [(n["neck"], chest, _o("neck", scale=scale)), (n["head"], n["neck"], _o("head", scale=scale))]
    ends = {n["head"]: _o("head_end", scale=scale)}
    for s in ("L", "R"):
        up = chest
        if clav:
            rows.append((n["clav" + s], chest, _o("clav", s, scale)))
            up = n["clav" + s]
        rows += [
            (n["upper" + s], up, _o("clav_side", s, scale)),
            (n["fore" + s], n["upper" + s], _o("upper", s, scale)),
            (n["hand" + s], n["fore" + s], _o("fore", s, scale)),
        ]
        ends[n["hand" + s]] = _o("hand_end", s, scale)
        rows += [
            (n["thigh" + s], n["root"], _o("hipL", s, scale)),
            (n["shin" + s], n["thigh" + s], _o("knee", s, scale)),
            (n["foot" + s], n["shin" + s], _o("ankle", s, scale)),
        ]
        if n.get("toe" + s):
            rows.append((n["toe" + s], n["foot" + s], _o("toe", s, scale)))
            ends[n["toe" + s]] = _o("toe_end", s, scale)
        else:
            ends[n["foot" + s]] = _o("toe", s, scale)
    if root_name:
        rows = [(root_name, None, (0.0, 0.0, 0.0))] + [(a, b or root_name, c) for a, b, c in rows]
    return rows, ends


def _table(prefix: str, left: str, right: str, pattern: dict) -> dict:
    out = {}
    for k, v in pattern.items():
        if k in ("root", "neck", "head"):
            out[k] = prefix + v
        else:
            out[k + "L"] = prefix + v.format(s=left)
            out[k + "R"] = prefix + v.format(s=right)
    return out


_MB = {
    "root": "Hips",
    "neck": "Neck",
    "head": "Head",
    "clav": "{s}Shoulder",
    "upper": "{s}Arm",
    "fore": "{s}ForeArm",
    "hand": "{s}Hand",
    "thigh": "{s}UpLeg",
    "shin": "{s}Leg",
    "foot": "{s}Foot",
    "toe": "{s}ToeBase",
}


def _spine(names: list[str], scale: float):
    return [(nm, _o("spine", scale=scale)) for nm in names]


def cmu_rows():
    """The 31-joint CMU conversion rig (``Hips``, ``LHipJoint``, ``LeftUpLeg``...), ASF units."""
    r = [("Hips", None, (0, 0, 0))]
    for s, sg, hip, leg, foot, toe, _end in (
        (
            "Left",
            "L",
            (1.85590, -1.73949, 0.84976),
            (2.36836, -6.50702, 0),
            (2.53268, -6.95849, 0),
            (0.15935, -0.43781, 1.94506),
            (0, 0, 1.00661),
        ),
        (
            "Right",
            "R",
            (-1.68297, -1.73949, 0.84976),
            (-2.44709, -6.72334, 0),
            (-2.43843, -6.69953, 0),
            (-0.20854, -0.57295, 2.02172),
            (0, 0, 1.05594),
        ),
    ):
        r += [
            (f"{sg}HipJoint", "Hips", (0, 0, 0)),
            (f"{s}UpLeg", f"{sg}HipJoint", hip),
            (f"{s}Leg", f"{s}UpLeg", leg),
            (f"{s}Foot", f"{s}Leg", foot),
            (f"{s}ToeBase", f"{s}Foot", toe),
        ]
    ends = {"LeftToeBase": (0, 0, 1.00661), "RightToeBase": (0, 0, 1.05594)}
    r += [
        ("LowerBack", "Hips", (0, 0, 0)),
        ("Spine", "LowerBack", (-0.01560, 2.23971, -0.03712)),
        ("Spine1", "Spine", (0.05490, 2.19225, -0.19086)),
        ("Neck", "Spine1", (0, 0, 0)),
        ("Neck1", "Neck", (-0.12403, 1.43168, 0.27585)),
        ("Head", "Neck1", (0.17855, 1.46173, -0.32578)),
    ]
    ends["Head"] = (0.07217, 1.51590, -0.14537)
    for s, sg, arm, fore, hand, idx, idx_end, th_end in (
        (
            "Left",
            "L",
            (3.27650, 0.85634, 0.05396),
            (4.96755, 0, 0),
            (3.35751, 0, 0),
            (0.79697, 0, 0),
            (0.64254, 0, 0),
            (0.65235, 0, 0.65235),
        ),
        (
            "Right",
            "R",
            (-3.24434, 1.02034, 0.34688),
            (-5.21859, 0, 0),
            (-3.36504, 0, 0),
            (-0.62044, 0, 0),
            (-0.50022, 0, 0),
            (-0.50786, 0, 0.50786),
        ),
    ):
        r += [
            (f"{s}Shoulder", "Spine1", (0, 0, 0)),
            (f"{s}Arm", f"{s}Shoulder", arm),
            (f"{s}ForeArm", f"{s}Arm", fore),
            (f"{s}Hand", f"{s}ForeArm", hand),
            (f"{s}FingerBase", f"{s}Hand", (0, 0, 0)),
            (f"{s}HandIndex1", f"{s}FingerBase", idx),
            (f"{sg}Thumb", f"{s}Hand", (0, 0, 0)),
        ]
        ends[f"{s}HandIndex1"] = idx_end
        ends[f"{sg}Thumb"] = th_end
    return r, ends


def family_rows(family: str):
    """``(rows, end_sites, units_to_m, up)`` of one naming family's rig."""
    if family == "cmu":
        rows, ends = cmu_rows()
        return rows, ends, 0.0254 / 0.45, "y"
    if family == "mixamo":  # a real Mixamo export (mixamorig7: prefix, end joints), cm
        return (*rig_headers.parse(rig_headers.MIXAMO), 0.01, "y")
    if family == "lafan":  # the LAFAN1 header (LeftToe, Spine2), cm, bone frames along x
        return (*rig_headers.parse(rig_headers.LAFAN1), 0.01, "y")
    if family == "smpl":  # SMPL/AMASS joint names, metres
        pat = {
            "root": "pelvis",
            "neck": "neck",
            "head": "head",
            "clav": "{s}_collar",
            "upper": "{s}_shoulder",
            "fore": "{s}_elbow",
            "hand": "{s}_wrist",
            "thigh": "{s}_hip",
            "shin": "{s}_knee",
            "foot": "{s}_ankle",
            "toe": "{s}_foot",
        }
        n = _table("", "left", "right", pat)
        return (*_humanoid(n, _spine(["spine1", "spine2", "spine3"], 1.0), 1.0), 1.0, "y")
    if family == "joint_root":  # the Bandai Namco dataset's 22-joint rig under joint_Root, cm
        return (*rig_headers.parse(rig_headers.BANDAI), 0.01, "y")
    if family == "daz":  # the cgspeed Daz-friendly header (hip, lButtock, lThigh...), cm
        return (*rig_headers.parse(rig_headers.DAZ), 0.01, "y")
    if family == "iclone":  # Character Creator CC_Base_ names with twist bones, cm
        pat = {
            "root": "Hip",
            "neck": "NeckTwist01",
            "head": "Head",
            "clav": "{s}_Clavicle",
            "upper": "{s}_Upperarm",
            "fore": "{s}_Forearm",
            "hand": "{s}_Hand",
            "thigh": "{s}_Thigh",
            "shin": "{s}_Calf",
            "foot": "{s}_Foot",
            "toe": "{s}_ToeBase",
        }
        n = _table("CC_Base_", "L", "R", pat)
        rows, ends = _humanoid(n, _spine(["CC_Base_Waist", "CC_Base_Spine01", "CC_Base_Spine02"], 100.0), 100.0)
        for s in ("L", "R"):
            rows.append((f"CC_Base_{s}_ThighTwist01", f"CC_Base_{s}_Thigh", (0.0, -20.0, 0.0)))
            rows.append(
                (f"CC_Base_{s}_UpperarmTwist01", f"CC_Base_{s}_Upperarm", ((1 if s == "L" else -1) * 12.0, 0, 0))
            )
        return rows, ends, 0.01, "y"
    if family == "unreal":  # UE mannequin names (pelvis, thigh_l, calf_l...), Z-up cm
        pat = {
            "root": "pelvis",
            "neck": "neck_01",
            "head": "head",
            "clav": "clavicle_{s}",
            "upper": "upperarm_{s}",
            "fore": "lowerarm_{s}",
            "hand": "hand_{s}",
            "thigh": "thigh_{s}",
            "shin": "calf_{s}",
            "foot": "foot_{s}",
            "toe": "ball_{s}",
        }
        n = _table("", "l", "r", pat)
        rows, ends = _humanoid(n, _spine(["spine_01", "spine_02", "spine_03"], 100.0), 100.0, root_name="root")
        return rows, ends, 0.01, "z"
    if family == "rokoko":  # Rokoko Studio names (LeftThigh, LeftShin, Spine1..4), cm
        pat = {**_MB, "thigh": "{s}Thigh", "shin": "{s}Shin", "toe": "{s}Toe"}
        n = _table("", "Left", "Right", pat)
        return (*_humanoid(n, _spine(["Spine1", "Spine2", "Spine3", "Spine4"], 100.0), 100.0), 0.01, "y")
    if family == "xsens":  # Xsens MVN names (Pelvis, L5, L3, T12, T8, RightUpperLeg...), cm
        pat = {
            "root": "Pelvis",
            "neck": "Neck",
            "head": "Head",
            "clav": "{s}Shoulder",
            "upper": "{s}UpperArm",
            "fore": "{s}ForeArm",
            "hand": "{s}Hand",
            "thigh": "{s}UpperLeg",
            "shin": "{s}LowerLeg",
            "foot": "{s}Foot",
            "toe": "{s}Toe",
        }
        n = _table("", "Left", "Right", pat)
        return (*_humanoid(n, _spine(["L5", "L3", "T12", "T8"], 100.0), 100.0), 0.01, "y")
    raise KeyError(family)


FAMILIES = ("cmu", "mixamo", "lafan", "smpl", "joint_root", "daz", "iclone", "unreal", "rokoko", "xsens")

#: Expected source joint of a few canonical joints, per family.
EXPECTED = {
    "cmu": {
        "root": "Hips",
        "lhip": "LeftUpLeg",
        "lknee": "LeftLeg",
        "lclavicle": "LeftShoulder",
        "lshoulder": "LeftArm",
        "chest": "Spine1",
        "lowerneck": "Neck1",
        "upperneck": "Head",
    },
    "mixamo": {
        "root": "mixamorig7:Hips",
        "lhip": "mixamorig7:LeftUpLeg",
        "ltoe": "mixamorig7:LeftToeBase",
        "lshoulder": "mixamorig7:LeftArm",
        "chest": "mixamorig7:Spine2",
        "upperback": "mixamorig7:Spine1",
        "upperneck": "mixamorig7:Head",
    },
    "lafan": {"ltoe": "LeftToe", "chest": "Spine2", "lelbow": "LeftForeArm"},
    "smpl": {
        "root": "pelvis",
        "lhip": "left_hip",
        "lknee": "left_knee",
        "lankle": "left_ankle",
        "ltoe": "left_foot",
        "lclavicle": "left_collar",
        "lshoulder": "left_shoulder",
        "chest": "spine3",
    },
    "joint_root": {"root": "Hips", "lhip": "UpperLeg_L", "rwrist": "Hand_R", "chest": "Chest"},
    "daz": {"root": "hip", "lhip": "lThigh", "lshoulder": "lShldr", "chest": "chest"},
    "iclone": {"root": "CC_Base_Hip", "lhip": "CC_Base_L_Thigh", "lowerneck": "CC_Base_NeckTwist01"},
    "unreal": {"root": "pelvis", "lhip": "thigh_l", "lknee": "calf_l", "lshoulder": "upperarm_l", "ltoe": "ball_l"},
    "rokoko": {"lhip": "LeftThigh", "lknee": "LeftShin", "chest": "Spine4"},
    "xsens": {"root": "Pelvis", "rhip": "RightUpperLeg", "chest": "T8", "lowerback": "L5", "upperback": "T12"},
}


def _motion(rows, frames: int, fps: float, up: str, units: float, seed: int) -> np.ndarray:
    """Channel values (frames, 6 + 3 (J - 1)) in ZXY Euler degrees for a Y-up rig."""
    rng = np.random.default_rng(seed)
    t = np.arange(frames) / fps
    ph = 2 * np.pi * 1.0 * t  # one stride per second
    data = []
    walk = 1.2 * t / units  # 1.2 m/s forward, in file units
    height = 0.95 / units
    heading = 20.0 * np.sin(0.3 * t)
    data += [0.3 / units * np.sin(0.5 * t), height + 0.02 / units * np.cos(2 * ph), walk]
    data += [heading, 3 * np.sin(2 * ph), 2 * np.sin(ph)]  # Z, X, Y rotations of the root
    for name, _parent, _ in rows[1:]:
        low = name.lower()
        z = x = y = np.zeros_like(t)
        side = 1.0 if re.search(r"Left|left|_L\b|_l$|^l[A-Z]|L_|^L[A-Z]", name) else -1.0
        phase = ph if side > 0 else ph + np.pi
        if any(k in low for k in ("upleg", "thigh", "upperleg", "_hip")) and "twist" not in low:
            x = -25 * np.sin(phase)  # hip flexion about the lateral axis
            y = 4 * np.sin(phase + 1)  # a little real twist
        elif any(k in low for k in ("leg", "shin", "calf", "knee")) and "up" not in low and "twist" not in low:
            x = 30 + 30 * np.sin(phase + 1.2)  # knee flexion, 0..60 degrees
        elif any(k in low for k in ("forearm", "lowerarm", "elbow")) and "twist" not in low:
            y = -side * (35 + 25 * np.sin(phase))  # elbow flexion about the vertical axis
        elif any(k in low for k in ("arm", "shldr", "shoulder")) and "fore" not in low and "lower" not in low:
            z = -side * (60 + 10 * np.sin(phase))  # arms down from the T-pose
            x = 15 * np.sin(phase + np.pi)
        elif any(k in low for k in ("spine", "abdomen", "chest", "neck", "waist", "l5", "l3", "t12", "t8")):
            z, x, y = 2 * np.sin(ph), 3 * np.sin(ph + 0.5), 4 * np.sin(ph + 1.0)
        jitter = rng.normal(0, 0.3, (3, frames))
        data += [z + jitter[0], x + jitter[1], y + jitter[2]]
    return np.stack(data, axis=1)


#: Families whose OFFSETs are in each joint's own bone frame (zero pose not a T-pose).
LOCAL_FRAMES = ("lafan", "joint_root")


def _with_bone_frames(data: np.ndarray, rows) -> np.ndarray:
    """The same motion on a rig whose joints rest in bone frames: each local rotation
    ``L`` of the T-pose rig becomes ``G_parent^-1 L G_joint`` (:func:`rig_headers.tpose_frames`)."""
    from engine.kinematics import quaternion as Q

    frames = rig_headers.tpose_frames(rows)
    g = {n: Q.from_matrix(m[None])[0] for n, m in frames.items()}
    out = data.copy()
    order = np.array(["z", "x", "y"])
    for k, (name, parent, _) in enumerate(rows):
        cols = slice(3 + 3 * k, 6 + 3 * k)
        q = Q.from_euler(np.radians(data[:, cols]), np.broadcast_to(order, (len(data), 3)))
        left = Q.conjugate(g[parent]) if parent is not None else np.array([1.0, 0.0, 0.0, 0.0])
        q = Q.mul(Q.mul(np.broadcast_to(left, q.shape), q), np.broadcast_to(g[name], q.shape))
        out[:, cols] = np.degrees(Q.to_euler(q, np.broadcast_to(order, (len(data), 3))))
    return out


def _root_under_hub(data: np.ndarray, hub_offset: np.ndarray) -> np.ndarray:
    """Move a top node's position channels so that its child (the hips, ``hub_offset``
    from it) walks where the clip's root walked."""
    from engine.kinematics import quaternion as Q

    order = np.broadcast_to(np.array(["z", "x", "y"]), (len(data), 3))
    q = Q.from_euler(np.radians(data[:, 3:6]), order)
    out = data.copy()
    out[:, :3] -= Q.rotate(q, np.broadcast_to(hub_offset, (len(data), 3)))
    return out


def _turn_x90(data: np.ndarray) -> np.ndarray:
    """Channels of the same motion seen in axes turned +90 degrees about X (Y-up -> Z-up)."""
    from engine.kinematics import quaternion as Q

    out = data.copy()
    out[:, 1], out[:, 2] = -data[:, 2], data[:, 1]
    eul = np.radians(data[:, 3:].reshape(len(data), -1, 3))
    order = np.broadcast_to(np.array(["z", "x", "y"]), eul.shape)
    q = Q.from_euler(eul, order)
    turn = np.broadcast_to(Q.from_axis_angle(np.array([1.0, 0.0, 0.0]), np.array([np.pi / 2])), q.shape)
    q = Q.mul(Q.mul(turn, q), Q.conjugate(turn))  # offsets turn too: every rotation is conjugated
    out[:, 3:] = np.degrees(Q.to_euler(q, order)).reshape(len(data), -1)
    return out


def write_family_bvh(path: Path, family: str, frames: int = 240, fps: float = 60.0, seed: int = 0) -> Path:
    """Write the synthetic clip of ``family`` to ``path`` and return it."""
    rows, ends, units, up = family_rows(family)
    children: dict[str | None, list] = {}
    for r in rows:
        children.setdefault(r[1], []).append(r)
    order = []

    def zup(v):
        return (v[0], -v[2], v[1]) if up == "z" else tuple(v)

    lines = ["HIERARCHY"]

    def emit(row, depth):
        name, parent, off = row
        ind = "  " * depth
        lines.append(f"{ind}{'ROOT' if parent is None else 'JOINT'} {name}")
        lines.append(f"{ind}{{")
        lines.append(f"{ind}  OFFSET {' '.join(f'{v:.6f}' for v in zup(off))}")
        if parent is None:
            lines.append(f"{ind}  CHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation")
        else:
            lines.append(f"{ind}  CHANNELS 3 Zrotation Xrotation Yrotation")
        order.append(name)
        for child in children.get(name, []):
            emit(child, depth + 1)
        if name in ends:
            end = " ".join(f"{v:.6f}" for v in zup(ends[name]))
            lines.extend([f"{ind}  End Site", f"{ind}  {{", f"{ind}    OFFSET {end}", f"{ind}  }}"])
        lines.append(f"{ind}}}")

    emit(rows[0], 0)
    by_name = {r[0]: r for r in rows}
    data = _motion([by_name[n] for n in order], frames, fps, up, units, seed)
    if family in LOCAL_FRAMES:
        data = _with_bone_frames(data, [by_name[n] for n in order])
    if family == "joint_root":  # joint_Root sits under the hips: its channels place the hips' walk
        data = _root_under_hub(data, np.array(by_name[order[1]][2], float))
    if up == "z":  # Y-up motion written for a Z-up rig: turn the whole rig +90 degrees about X
        data = _turn_x90(data)
    lines += ["MOTION", f"Frames: {frames}", f"Frame Time: {1.0 / fps:.6f}"]
    lines += [" ".join(f"{v:.5f}" for v in row) for row in data]
    Path(path).write_text("\n".join(lines) + "\n")
    return Path(path)
