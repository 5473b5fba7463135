"""The documented twist rules for rigs that lack the defining landmarks.

A canonical walk is written onto a CMU/MotionBuilder-like rig: no knuckles that are
children of the hand but a ``FingerBase`` on the wrist with an index joint, and a thumb
on the wrist; no eyes. With rotated joint axes (and the hand's twist undone by its finger
joints) the wrists read back as on a rig with knuckles, and the neck follows its rule."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from engine import skeleton as sk
from engine.kinematics import quaternion as Q
from engine.motion import retarget_body as RB
from engine.motion.retarget_strategy import CURRENT
from tests.engine.test_retarget_body import _axis_angle, _conventions, canonical_walk, write_rig

FINGERS = ("FingerBase", "HandIndex1", "Thumb")


def _thumb_tip(side: str) -> np.ndarray:
    """Where the thumb rule expects the thumb's tip (metres, canonical rest): half-way
    between the hand's direction and the thumb side turned THUMB_PALM_DEG to the palm."""
    b0 = RB.canonical_body_frames()[f"{side}wrist"]
    t = np.radians(RB.THUMB_PALM_DEG)
    palm = 1.0 if side == "l" else -1.0  # frame +z is the palm on the left hand, -z on the right
    local = np.array([1.0, np.cos(t), palm * np.sin(t)]) / np.sqrt(2.0)
    return 0.05 * Q.rotate(b0, local)


def _cmu_hands(rows):
    """Hands as the CMU rig draws them: a FingerBase on the wrist with an index joint
    along the hand, and a thumb on the wrist whose end site is its tip."""
    names = [r[0] for r in rows]
    for side, hand in (("l", "LeftHand"), ("r", "RightHand")):
        w = names.index(hand)
        along = RB.canonical_body_frames()[f"{side}wrist"]
        prefix = hand[: -len("Hand")]
        rows.append([f"{prefix}FingerBase", w, np.zeros(3), None])
        rows.append(
            [
                f"{prefix}HandIndex1",
                len(rows) - 1,
                0.08 * Q.rotate(along, np.array([1.0, 0, 0])),
                np.array([0.0, 0.0, 0.0]),
            ]
        )
        rows.append([f"{prefix}Thumb", w, np.zeros(3), _thumb_tip(side)])
    return rows


@pytest.fixture(scope="module")
def cmu_like(tmp_path_factory):
    from engine.motion.bvh import load_bvh
    from engine.motion.retarget import retarget

    tmp = tmp_path_factory.mktemp("rules")
    local, root = canonical_walk(120)
    ref = retarget(load_bvh(write_rig(tmp / "knuckles.bvh", local, root)), strategy=CURRENT)
    axes = _conventions(np.random.default_rng(7))
    for side in ("Left", "Right"):
        for f in FINGERS:
            axis = np.random.default_rng(len(f)).normal(size=3)
            axes[f"{side}{f}"] = _axis_angle(axis / np.linalg.norm(axis), 70.0 + len(f))
    out = {"knuckles": ref}
    for name, kw in {"plain": {}, "rotated_axes": {"frames_c": axes}}.items():
        path = write_rig(tmp / f"{name}.bvh", local, root, landmarks=False, rest=_cmu_hands, **kw)
        out[name] = retarget(load_bvh(path), strategy=CURRENT)
    return out


def _deg(a, b, joint) -> np.ndarray:
    k = sk.JOINT_INDEX[joint]
    return np.degrees(Q.angle(a.local_rot[:, k], b.local_rot[:, k]))


@pytest.mark.parametrize("variant", ["plain", "rotated_axes"])
def test_a_hand_with_finger_base_and_thumb_reads_back_as_with_knuckles(cmu_like, variant):
    ref = cmu_like["knuckles"][0]
    motion, rep = cmu_like[variant]
    assert rep.twist_rules["lwrist"] == rep.twist_rules["rwrist"] == "thumb"
    assert "lwrist" not in rep.source_twist_joints
    for joint in ("lwrist", "rwrist"):
        assert _deg(ref, motion, joint).max() < 1.0, joint


def test_the_thumb_rule_changes_the_source_twist_reading(cmu_like, tmp_path):
    """Without body-defined twist (the source's hand axes) the rotated axes show."""
    from engine.motion.bvh import load_bvh
    from engine.motion.retarget import retarget

    local, root = canonical_walk(60)
    axes = _conventions(np.random.default_rng(7))
    raw = load_bvh(write_rig(tmp_path / "v3.bvh", local, root, landmarks=False, rest=_cmu_hands, frames_c=axes))
    old = retarget(raw, strategy=dataclasses.replace(CURRENT, body_twist=False))[0]
    new = retarget(raw, strategy=CURRENT)[0]
    ref = cmu_like["knuckles"][0].slice(0, 60)
    assert _deg(ref, old, "lwrist").mean() > 5.0
    assert _deg(ref, new, "lwrist").max() < 1.0


@pytest.mark.parametrize("variant", ["plain", "rotated_axes"])
def test_a_head_without_eyes_faces_as_the_chest_and_keeps_its_bone(cmu_like, variant):
    truth = cmu_like["knuckles"][0]
    motion, rep = cmu_like[variant]
    assert rep.twist_rules["lowerneck"] == rep.twist_rules["upperneck"] == "head frame"
    assert rep.source_twist_joints == []
    _, rot = motion.fk()
    _, rot_t = truth.fk()
    head, chest = sk.JOINT_INDEX["upperneck"], sk.JOINT_INDEX["chest"]
    n = len(rot)

    def axis(r, v):
        return Q.rotate(r, np.broadcast_to(np.asarray(v, float), (n, 3)))

    up, up_t = axis(rot[:, head], sk.END_SITES["upperneck"]), axis(rot_t[:, head], sk.END_SITES["upperneck"])
    cos = (up * up_t).sum(-1) / np.linalg.norm(up, axis=-1) / np.linalg.norm(up_t, axis=-1)
    assert np.degrees(np.arccos(np.clip(cos, -1, 1))).max() < 1.0  # the head bone's swing is the source's
    e = sk.END_SITES["upperneck"] / np.linalg.norm(sk.END_SITES["upperneck"])
    rest_left = np.array([1.0, 0, 0]) - e[0] * e  # the head's left, square to its bone
    left = axis(rot[:, head], rest_left / np.linalg.norm(rest_left))
    chest_left = axis(rot[:, chest], [1.0, 0, 0])
    u = up / np.linalg.norm(up, axis=-1, keepdims=True)
    square = chest_left - (chest_left * u).sum(-1, keepdims=True) * u
    square /= np.linalg.norm(square, axis=-1, keepdims=True)
    assert np.degrees(np.arccos(np.clip((left * square).sum(-1), -1, 1))).max() < 1.0  # no twist of its own
    # the walk turns its head (20 degrees of lower-neck twist): a rule without face landmarks cannot see it
    assert _deg(truth, motion, "lowerneck").max() > 10.0
    assert _deg(cmu_like["plain"][0], motion, "lowerneck").max() < 1.0


def test_info_names_the_rule_each_joint_used(tmp_path, capsys):
    from engine.cli.info import describe
    from engine.cli.main import main

    local, root = canonical_walk(30)
    path = write_rig(tmp_path / "cmu_like.bvh", local, root, landmarks=False, rest=_cmu_hands)
    out = describe(path, None, None)
    assert out["twist_rule"] == {
        "lwrist": "thumb",
        "rwrist": "thumb",
        "lowerneck": "head frame",
        "upperneck": "head frame",
    }
    assert out["source_twist"] == [] and out["rotations_copied"] is False
    assert main(["info", str(path)]) == 0
    assert "twist rule    lwrist (thumb), rwrist (thumb), lowerneck (head frame)" in capsys.readouterr().out


def test_info_on_the_canonical_rig_says_its_rotations_are_copied(shared_mocap, capsys):
    """The canonical rig's rotations are canonical ones: none of its joints keeps a
    "source twist" for want of landmarks."""
    from engine.cli.info import describe
    from engine.cli.main import main

    path = shared_mocap / "dragposer" / "example_2.bvh"
    out = describe(path, None, None)
    assert out["rig"] == "dragposer" and out["rotations_copied"] is True
    assert out["source_twist"] == [] and out["body_twist"] == [] and out["twist_rule"] == {}
    assert main(["info", str(path)]) == 0
    text = capsys.readouterr().out
    assert "rotations     copied as they are" in text and "source twist" not in text


@pytest.mark.parametrize("hand_axes", ["plain", "half_turn"])
def test_a_hand_without_fingers_keeps_its_swing_and_no_twist(tmp_path, hand_axes):
    """No knuckles, finger base or thumb: the wrist keeps the swing of the source's hand
    relative to the forearm and no twist about the hand's direction, whichever way the
    rig's hand axes are turned about the bone."""
    from engine.motion.bvh import load_bvh
    from engine.motion.joint_stats import twist_deg
    from engine.motion.retarget import retarget

    local, root = canonical_walk(90)
    truth = retarget(load_bvh(write_rig(tmp_path / "k.bvh", local, root)), strategy=CURRENT)[0]
    half = (
        {
            n: _axis_angle(sk.END_SITES[j] / np.linalg.norm(sk.END_SITES[j]), 180.0)  # about the hand's direction
            for n, j in (("LeftHand", "lwrist"), ("RightHand", "rwrist"))
        }
        if hand_axes == "half_turn"
        else {}
    )
    motion, rep = retarget(
        load_bvh(write_rig(tmp_path / "bare.bvh", local, root, landmarks=False, frames_c=half)), strategy=CURRENT
    )
    assert rep.twist_rules["lwrist"] == rep.twist_rules["rwrist"] == "no twist"
    for joint in ("lwrist", "rwrist"):
        k, axis = sk.JOINT_INDEX[joint], sk.END_SITES[joint]
        assert np.abs(twist_deg(motion.local_rot[:, k], axis)).max() < 1e-6
        bone = np.broadcast_to(axis / np.linalg.norm(axis), (len(local), 3))
        a, b = Q.rotate(motion.local_rot[:, k], bone), Q.rotate(truth.local_rot[:, k], bone)
        assert np.degrees(np.arccos(np.clip((a * b).sum(-1), -1, 1))).max() < 1.0, joint
        assert np.abs(twist_deg(truth.local_rot[:, k], axis)).max() > 10  # the truth does twist
