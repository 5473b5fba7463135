"""Body-defined rotations: the same body motion gives the same canonical rotations on any rig.

A synthetic canonical walk is written onto rigs that differ only in conventions (per-joint
bone axes, an A-pose rest, twist axes turned half a turn, a twist the thigh and forearm
carry and their children undo, bone axes along +X with the right side's mirrored) and read
back: the rotations agree within 1 degree."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from engine import skeleton as sk
from engine.kinematics import quaternion as Q
from engine.motion.retarget_frames import CANON_LANDMARKS
from engine.motion.retarget_strategy import CURRENT

NAMES = {
    "root": "Hips",
    "lhip": "LeftUpLeg",
    "lknee": "LeftLeg",
    "lankle": "LeftFoot",
    "ltoe": "LeftToeBase",
    "rhip": "RightUpLeg",
    "rknee": "RightLeg",
    "rankle": "RightFoot",
    "rtoe": "RightToeBase",
    "lowerback": "Spine",
    "upperback": "Spine1",
    "chest": "Spine2",
    "lowerneck": "Neck",
    "upperneck": "Head",
    "lclavicle": "LeftShoulder",
    "lshoulder": "LeftArm",
    "lelbow": "LeftForeArm",
    "lwrist": "LeftHand",
    "rclavicle": "RightShoulder",
    "rshoulder": "RightArm",
    "relbow": "RightForeArm",
    "rwrist": "RightHand",
}
# landmark joints (children of their anchor, so they move rigidly with it)
EXTRA = {
    "LeftEye": "l_eye",
    "RightEye": "r_eye",
    "LeftHandIndex1": "l_index",
    "LeftHandPinky1": "l_pinky",
    "RightHandIndex1": "r_index",
    "RightHandPinky1": "r_pinky",
}


def _axis_angle(axis, deg):
    return Q.from_axis_angle(np.broadcast_to(np.asarray(axis, float), np.shape(deg) + (3,)), np.radians(deg))


def canonical_walk(frames: int = 180) -> tuple[np.ndarray, np.ndarray]:
    """Local rotations (F, 22, 4) and root positions (F, 3) of a canonical walk whose knees
    and elbows stay bent (at least 35 degrees) and whose hands, feet and head turn."""
    t = np.arange(frames) / 60.0
    ph = 2 * np.pi * 0.9 * t
    rot = np.tile(np.array([1.0, 0, 0, 0]), (frames, sk.NUM_JOINTS, 1))

    def put(name, q):
        j = sk.JOINT_INDEX[name]
        rot[:, j] = Q.mul(rot[:, j], q)

    put("root", _axis_angle([0, 0, 1], 25 * np.sin(0.4 * ph)))
    for s, sign in (("l", 1), ("r", -1)):
        put(f"{s}hip", _axis_angle([1, 0, 0], 25 * sign * np.sin(ph)))
        put(f"{s}hip", _axis_angle([0, 0, 1], 10 * np.sin(0.7 * ph + sign)))
        put(f"{s}knee", _axis_angle([1, 0, 0], -(55 + 20 * np.sin(ph + sign))))
        put(f"{s}ankle", _axis_angle([1, 0, 0], 15 * np.sin(ph)))
        put(f"{s}ankle", _axis_angle([0, 1, 0], 10 * np.sin(0.5 * ph)))
        put(f"{s}toe", _axis_angle([1, 0, 0], 10 * np.sin(ph)))
        put(f"{s}shoulder", _axis_angle([0, 1, 0], sign * (60 + 10 * np.sin(ph))))
        put(f"{s}shoulder", _axis_angle([1, 0, 0], 20 * np.sin(ph - sign)))
        put(f"{s}elbow", _axis_angle([0, 0, 1], sign * (60 + 20 * np.sin(ph))))
        put(f"{s}wrist", _axis_angle([1, 0, 0], 30 * np.sin(0.8 * ph)))
        put(f"{s}wrist", _axis_angle([0, 0, 1], 20 * np.sin(0.6 * ph)))
    put("lowerneck", _axis_angle([0, 0, 1], 20 * np.sin(0.5 * ph)))
    put("upperneck", _axis_angle([1, 0, 0], 15 * np.sin(0.3 * ph)))
    put("chest", _axis_angle([0, 0, 1], 8 * np.sin(ph)))
    root = np.stack([0.05 * np.sin(ph), -1.2 * t, 0.95 + 0.02 * np.cos(2 * ph)], axis=-1)
    return rot, root


def _hierarchy(landmarks: bool = True):
    """(name, parent index, offset (3,), end site or None) rows, canonical rest (T-pose),
    metres; with ``landmarks``, eye and knuckle joints too."""
    rows = []
    for j, canon in enumerate(sk.JOINT_NAMES):
        end = sk.END_SITES.get(canon)
        rows.append([NAMES[canon], sk.PARENTS[j], sk.REST_OFFSETS[j].copy(), None if end is None else np.array(end)])
    for name, lm in EXTRA.items() if landmarks else ():
        anchor, off = CANON_LANDMARKS[lm]
        rows.append([name, sk.JOINT_INDEX[anchor], np.asarray(off, float).copy(), np.array([0.0, -0.01, 0.0])])
    return rows


def _straight_elbows(rows, bend_deg: float = 0.0):
    """Make each elbow straight in the zero pose (the wrist's OFFSET on the elbow's
    direction), then bend the left forearm by ``bend_deg`` degrees (its OFFSET, the hand's
    joints and end sites turning rigidly)."""
    names = [r[0] for r in rows]
    for mid, end in (("LeftForeArm", "LeftHand"), ("RightForeArm", "RightHand")):
        m, e = names.index(mid), names.index(end)
        rows[e][2] = rows[m][2] / np.linalg.norm(rows[m][2]) * np.linalg.norm(rows[e][2])
    if bend_deg:
        e = names.index("LeftHand")
        d = rows[e][2] / np.linalg.norm(rows[e][2])
        axis = np.array([0.0, 0.0, 1.0]) - d[2] * d  # the vertical off the bone: the walk's elbow hinge
        turn = _axis_angle(axis / np.linalg.norm(axis), bend_deg)
        below = {e}
        for j, r in enumerate(rows):
            if r[1] in below or j == e:
                below.add(j)
                r[2] = Q.rotate(turn, r[2])
                r[3] = None if r[3] is None else Q.rotate(turn, r[3])
    return rows


def write_rig(path, local, root, frames_c=None, twist=None, landmarks=True, rest=None, hub=False, fps=60.0):
    """Write the canonical motion onto a rig with per-joint constant frames ``frames_c``
    (joint name -> quaternion ``C``: ``G_rig = G C``, OFFSETs and end sites re-expressed)
    and ``twist`` (upper joint name -> degrees (F,)): that joint carries a twist about its
    bone that its child undoes; ``rest`` edits the zero pose's rows (see :func:`_straight_elbows`).
    World positions are the canonical ones unless ``rest`` changes the OFFSETs. With
    ``hub``, a static ``joint_Root`` sits above the hips and every joint has 6 channels
    (positions: the OFFSET, the hips' the trajectory), as game-studio rigs write them.
    ``fps`` is the header's rate."""
    rows = _hierarchy(landmarks)
    rows = rest(rows) if rest else rows
    if hub:
        rows = [["joint_Root", -1, np.zeros(3), None]] + [[r[0], r[1] + 1, r[2], r[3]] for r in rows]
        local = np.concatenate([np.tile(np.array([1.0, 0, 0, 0]), (len(local), 1, 1)), local], axis=1)
    n, f = len(rows), len(local)
    full = np.tile(np.array([1.0, 0, 0, 0]), (f, n, 1))
    full[:, : local.shape[1]] = local
    c = np.tile(np.array([1.0, 0, 0, 0]), (n, 1))
    for i, r in enumerate(rows):
        if frames_c and r[0] in frames_c:
            c[i] = frames_c[r[0]]
    for name, deg in (twist or {}).items():
        i = [r[0] for r in rows].index(name)
        child = next(k for k, r in enumerate(rows) if r[1] == i)
        t = _axis_angle(rows[child][2] / np.linalg.norm(rows[child][2]), deg)
        full[:, i] = Q.mul(full[:, i], t)
        full[:, child] = Q.mul(Q.conjugate(t), full[:, child])
    out = np.empty_like(full)
    for i, r in enumerate(rows):
        cp = c[r[1]] if r[1] >= 0 else np.array([1.0, 0, 0, 0])
        out[:, i] = Q.mul(Q.mul(np.broadcast_to(Q.conjugate(cp), (f, 4)), full[:, i]), np.broadcast_to(c[i], (f, 4)))
    euler = np.degrees(Q.to_euler(Q.normalize(out), np.broadcast_to(np.array(["z", "y", "x"]), (f, n, 3))))
    lines = ["HIERARCHY"]

    def emit(i, depth):
        r, pad = rows[i], "  " * depth
        cp = c[r[1]] if r[1] >= 0 else np.array([1.0, 0, 0, 0])
        off = Q.rotate(Q.conjugate(cp), r[2])
        lines.append(f"{pad}{'ROOT' if r[1] < 0 else 'JOINT'} {r[0]}")
        lines.append(f"{pad}{{")
        lines.append(f"{pad}  OFFSET {off[0]:.6f} {off[1]:.6f} {off[2]:.6f}")
        lines.append(
            f"{pad}  CHANNELS {'6 Xposition Yposition Zposition ' if r[1] < 0 or hub else '3 '}"
            "Zrotation Yrotation Xrotation"
        )
        kids = [k for k, q in enumerate(rows) if q[1] == i]
        for k in kids:
            emit(k, depth + 1)
        if not kids or r[3] is not None:
            e = Q.rotate(Q.conjugate(c[i]), r[3] if r[3] is not None else np.array([0.0, 0.0, 0.05]))
            lines.extend(
                [f"{pad}  End Site", f"{pad}  {{", f"{pad}    OFFSET {e[0]:.6f} {e[1]:.6f} {e[2]:.6f}", f"{pad}  }}"]
            )
        lines.append(f"{pad}}}")

    emit(0, 0)
    order = []

    def walk(i):
        order.append(i)
        for k, q in enumerate(rows):
            if q[1] == i:
                walk(k)

    walk(0)
    lines += ["MOTION", f"Frames: {f}", f"Frame Time: {1.0 / fps:.7f}"]
    for t in range(f):
        vals = [] if hub else [*root[t]]
        for i in order:
            if hub:
                vals += list(
                    root[t] if i == 1 else Q.rotate(Q.conjugate(c[rows[i][1]]), rows[i][2]) if i else np.zeros(3)
                )
            vals += list(euler[t, i])
        lines.append(" ".join(f"{v:.6f}" for v in vals))
    path.write_text("\n".join(lines) + "\n")
    return path


def _conventions(rng) -> dict:
    """Per-joint rest conventions: random bone axes, half-turn twist axes, an A-pose."""
    c = {}
    for name in [*NAMES.values(), *EXTRA]:
        axis = rng.normal(size=3)
        c[name] = _axis_angle(axis / np.linalg.norm(axis), rng.uniform(-180, 180))
    return c


def _bone_x(mirrored: bool) -> dict:
    """Per-joint frames whose local +X runs along the bone (towards the child, the end site
    for leaves; up for the hips), as game rigs draw them; ``mirrored``: the right side's +X
    runs the other way (towards the parent), so its twist axis is mirrored."""
    from engine.motion.joint_stats import joint_axis

    c = {}
    for canon, name in NAMES.items():
        axis = joint_axis(canon)
        if mirrored and canon.startswith("r"):
            axis = -axis
        c[name] = Q.from_to(np.array([1.0, 0.0, 0.0]), axis)
    return c


@pytest.fixture(scope="module")
def rigs(tmp_path_factory):
    from engine.motion.bvh import load_bvh
    from engine.motion.retarget import retarget

    tmp = tmp_path_factory.mktemp("body")
    local, root = canonical_walk()
    ph = np.linspace(0, 4 * np.pi, len(local))
    half = {n: _axis_angle([1, 0, 0], 180.0) for n in ("LeftArm", "LeftForeArm", "RightUpLeg", "RightLeg", "LeftHand")}
    apose = {n: _axis_angle([0, 1, 0], s * 45.0) for n, s in (("LeftArm", 1), ("RightArm", -1))}
    variants = {
        "tpose": {},
        "random_axes": {"frames_c": _conventions(np.random.default_rng(1))},
        "half_turn_twist_axes": {"frames_c": half},
        "apose": {"frames_c": apose},
        "bone_axes_along_x": {"frames_c": _bone_x(False)},
        "bone_axes_along_x_mirrored": {"frames_c": _bone_x(True)},
        "child_undoes_twist": {"twist": {n: 150 * np.sin(ph) for n in ("LeftUpLeg", "RightUpLeg", "LeftForeArm")}},
    }
    out = {}
    for key, strategy in (("source_twist", dataclasses.replace(CURRENT, body_twist=False)), ("body_twist", CURRENT)):
        for name, kw in variants.items():
            raw = load_bvh(write_rig(tmp / f"{name}.bvh", local, root, **kw))
            out[key, name] = retarget(raw, strategy=strategy)
    return out


def _diff(a, b) -> np.ndarray:
    return np.degrees(Q.angle(a.local_rot, b.local_rot)).max(0)


@pytest.mark.parametrize(
    "variant",
    [
        "random_axes",
        "half_turn_twist_axes",
        "apose",
        "bone_axes_along_x",
        "bone_axes_along_x_mirrored",
        "child_undoes_twist",
    ],
)
def test_rest_conventions_do_not_change_the_canonical_rotations(rigs, variant):
    ref, rep = rigs["body_twist", "tpose"]
    other, rep2 = rigs["body_twist", variant]
    assert rep.mapping == rep2.mapping
    worst = _diff(ref, other)
    assert worst.max() < 1.0, dict(zip(sk.JOINT_NAMES, np.round(worst, 2)))


def test_the_source_twist_a_child_undoes_changed_the_older_definition(rigs):
    """The defect body-defined twist removes: without it the thigh keeps its own twist."""
    worst = _diff(rigs["source_twist", "tpose"][0], rigs["source_twist", "child_undoes_twist"][0])
    assert worst[sk.JOINT_INDEX["lhip"]] > 30 and worst[sk.JOINT_INDEX["lknee"]] > 30


def test_a_rig_without_face_or_fingers_uses_the_rules_and_says_so(rigs, tmp_path):
    from engine.motion.bvh import load_bvh
    from engine.motion.retarget import retarget

    full = rigs["body_twist", "tpose"][1]
    assert full.source_twist_joints == [] and "lwrist" in full.body_joints and "upperneck" in full.body_joints
    assert full.twist_rules == {}
    local, root = canonical_walk(60)
    text = write_rig(tmp_path / "bare.bvh", local, root, landmarks=False)
    rep = retarget(load_bvh(text), strategy=CURRENT)[1]
    assert rep.source_twist_joints == []
    assert rep.twist_rules == {
        "lwrist": "no twist",
        "rwrist": "no twist",
        "lowerneck": "head frame",
        "upperneck": "head frame",
    }


def test_models_strategy_comes_from_the_model_card(tmp_path):
    """The card names the current version; a version this program does not produce (3,
    retired, or 9, never made) is refused, naming the file and the field."""
    from engine.errors import UserError
    from engine.motion.retarget import models_strategy

    (tmp_path / "data.toml").write_text(f"retarget_version = {CURRENT.version}\n")
    assert models_strategy(tmp_path / "data.toml") is CURRENT
    assert models_strategy(tmp_path / "absent.toml") is CURRENT
    for version in (3, 9):
        (tmp_path / "bad.toml").write_text(f"retarget_version = {version}\n")
        with pytest.raises(
            UserError, match=f"bad.toml: retarget_version must be one of {CURRENT.version} .*got {version}"
        ):
            models_strategy(tmp_path / "bad.toml")


def test_straight_elbows_measures_the_bend_from_a_rest_drawn_bent(tmp_path):
    """A rig whose zero pose draws the forearm 17 degrees bent, with the T-pose rotations
    copied onto it (as the Daz rig's conversion did): ``straight_elbows`` reads the elbow
    as the T-pose rig does; without it the elbow is 17 degrees off."""
    from engine.motion.bvh import load_bvh
    from engine.motion.retarget import retarget
    from engine.motion.rigs import resolve_rig

    local, root = canonical_walk(90)
    ref = retarget(load_bvh(write_rig(tmp_path / "t.bvh", local, root, rest=_straight_elbows)), strategy=CURRENT)[0]
    raw = load_bvh(write_rig(tmp_path / "b.bvh", local, root, rest=lambda rows: _straight_elbows(rows, 17.0)))
    prof = resolve_rig(raw)
    elbow = sk.JOINT_INDEX["lelbow"]
    plain = retarget(raw, profile=prof, strategy=CURRENT)[0]
    assert np.degrees(Q.angle(plain.local_rot[:, elbow], ref.local_rot[:, elbow])).mean() > 10
    fixed = retarget(raw, profile=dataclasses.replace(prof, straight_elbows=True), strategy=CURRENT)[0]
    assert _diff(ref, fixed).max() < 1.0


def _straight_knees(rows, bend_deg: float = 0.0):
    """Make each leg straight in the zero pose (the ankle's OFFSET on the knee's direction),
    then draw the left knee ``bend_deg`` degrees bent with the hip-to-ankle line kept (the
    thigh turned forward, the shin back, both lengths kept; the foot turning with the shin)."""
    names = [r[0] for r in rows]
    for mid, end in (("LeftLeg", "LeftFoot"), ("RightLeg", "RightFoot")):
        m, e = names.index(mid), names.index(end)
        rows[e][2] = rows[m][2] / np.linalg.norm(rows[m][2]) * np.linalg.norm(rows[e][2])
    if bend_deg:
        m, e = names.index("LeftLeg"), names.index("LeftFoot")
        knee, shin = rows[m][2], rows[e][2]
        line = (knee + shin) / np.linalg.norm(knee + shin)
        a, b = np.linalg.norm(knee), np.linalg.norm(shin)
        thigh_turn = np.degrees(np.arcsin(b * np.sin(np.radians(bend_deg)) / np.linalg.norm(knee + shin)))
        side = np.cross(line, [0.0, -1.0, 0.0])  # the knee goes forward (-Y)
        new_knee = Q.rotate(_axis_angle(side / np.linalg.norm(side), -thigh_turn), knee)
        dk = float(new_knee @ line)
        new_shin = (dk + np.sqrt(dk * dk - a * a + b * b)) * line - new_knee
        turn = Q.from_to(shin, new_shin)
        rows[m][2], rows[e][2] = new_knee, new_shin
        below = {e}
        for j, r in enumerate(rows):
            if r[1] in below:
                below.add(j)
                r[2] = Q.rotate(turn, r[2])
            if j in below:
                r[3] = None if r[3] is None else Q.rotate(turn, r[3])
    return rows


def test_straight_knees_reads_a_leg_drawn_bent_along_its_hip_to_ankle_line(tmp_path):
    """A rig whose zero pose draws the left knee 7.7 degrees bent about an unchanged
    hip-to-ankle line (as the Daz rig does), the T-pose rotations copied onto it:
    ``straight_knees`` reads the whole leg as the straight-legged rig does with the
    strategy's ``straight_knees``; the current strategy ignores it and reads the drawn bend."""
    from engine.motion.bvh import load_bvh
    from engine.motion.retarget import retarget
    from engine.motion.rigs import resolve_rig

    knees = dataclasses.replace(CURRENT, straight_knees=True)
    local, root = canonical_walk(90)
    ref = retarget(load_bvh(write_rig(tmp_path / "t.bvh", local, root, rest=_straight_knees)), strategy=knees)[0]
    raw = load_bvh(write_rig(tmp_path / "b.bvh", local, root, rest=lambda rows: _straight_knees(rows, 7.7)))
    prof = dataclasses.replace(resolve_rig(raw), straight_knees=True)
    knee, hip = sk.JOINT_INDEX["lknee"], sk.JOINT_INDEX["lhip"]
    for strategy in (CURRENT, knees):
        plain = retarget(raw, profile=dataclasses.replace(prof, straight_knees=False), strategy=strategy)[0]
        assert np.degrees(Q.angle(plain.local_rot[:, knee], ref.local_rot[:, knee])).mean() > 5
    old = retarget(raw, profile=prof, strategy=CURRENT)[0]
    assert np.degrees(Q.angle(old.local_rot[:, knee], ref.local_rot[:, knee])).mean() > 5
    fixed = retarget(raw, profile=prof, strategy=knees)[0]
    assert _diff(ref, fixed).max() < 1.0, dict(zip(sk.JOINT_NAMES, np.round(_diff(ref, fixed), 2)))
    assert np.degrees(Q.angle(fixed.local_rot[:, hip], ref.local_rot[:, hip])).max() < 1.0


def _sole_toes(rows):
    """Put each toe's end site on the sole's line (horizontal in the zero pose, its length
    and its heading kept), where source rigs put their toe tips."""
    from engine.motion.retarget_body import sole_tip

    for side, name in (("l", "LeftToeBase"), ("r", "RightToeBase")):
        row = next(r for r in rows if r[0] == name)
        row[3] = sole_tip(side)
    return rows


def test_sole_toe_tips_read_a_toe_tip_on_the_sole_as_a_straight_toe(tmp_path):
    """The canonical walk on a rig whose toe tips lie on the sole's line (iClone's middle
    toe, the CMU rig's end site): with ``sole_toe_tips`` its toes read as the current
    strategy reads a rig whose tips are where the canonical end site points (on the floor,
    25 degrees below the toe), while the current strategy reads the sole tips about 25
    degrees bent. Only the toes change."""
    from engine.motion.bvh import load_bvh
    from engine.motion.retarget import retarget

    local, root = canonical_walk(90)
    sole = load_bvh(write_rig(tmp_path / "sole.bvh", local, root, rest=_sole_toes))
    floor = load_bvh(write_rig(tmp_path / "floor.bvh", local, root))
    toes = [sk.JOINT_INDEX["ltoe"], sk.JOINT_INDEX["rtoe"]]

    def toe_error(motion) -> float:
        return float(np.degrees(Q.angle(motion.local_rot[:, toes], local[:, toes])).mean())

    current = retarget(sole, strategy=CURRENT)[0]
    on_sole = retarget(sole, strategy=dataclasses.replace(CURRENT, sole_toe_tips=True))[0]
    assert toe_error(current) > 20.0
    assert toe_error(on_sole) < toe_error(retarget(floor, strategy=CURRENT)[0]) + 1.5 < 6.0
    others = [j for j in range(sk.NUM_JOINTS) if j not in toes]
    assert np.degrees(Q.angle(current.local_rot[:, others], on_sole.local_rot[:, others])).max() < 1e-3
