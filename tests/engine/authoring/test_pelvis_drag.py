"""The pelvis-only drag (issue 50, defect 4: "the squat lands on the toes"): Shift + drag
on the hips moves the pelvis alone, the feet planted flat where they stood, the legs bent
by their two bones, the upper body carried unchanged; a key made so bakes to the same pose."""

from __future__ import annotations

import numpy as np
import pytest

from engine import skeleton as sk
from engine.authoring.bake import bake
from engine.authoring.document import authoring_from_dict, authoring_to_dict, load_authoring, save_authoring
from engine.authoring.pose_mode import PoseMode
from engine.authoring.session import AuthoringSession
from engine.authoring.targets import JointTarget
from engine.errors import UserError
from engine.kinematics.fk import fk
from engine.solver.limb_ik import CARRIED

J = sk.JOINT_INDEX
FEET = [J[j] for j in ("lankle", "ltoe", "rankle", "rtoe")]
UPPER = sorted(CARRIED)  # the lower back and all above it: what the pelvis carries
FORWARD = np.array([0.0, -1.0, 0.0])  # heading 0 faces -Y


def squat(session: AuthoringSession, down: float = 0.35, back: float = 0.0, events: int = 8) -> None:
    start = session.hips_handle()
    for k in range(1, events + 1):
        session.drag_pelvis(start + np.array([0.0, back, -down]) * k / events)


def in_pelvis_frame(pose) -> np.ndarray:
    """Joint positions relative to the pelvis, in its own frame."""
    r = fk(pose.local_rot, pose.root_pos, np.zeros((sk.NUM_JOINTS, 3)))[1][0]
    w, x, y, z = r
    m = np.array(
        [
            [1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
            [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
            [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)],
        ]
    )
    return (pose.positions - pose.root_pos) @ m


@pytest.fixture
def session(vae):
    return AuthoringSession(PoseMode(vae, 1.75))


def test_lowering_the_pelvis_alone_keeps_the_feet_flat_and_the_upper_body(session):
    m = session.mode
    before = m.pose
    squat(session, 0.35)
    after = m.pose
    assert after.root_pos[2] == pytest.approx(before.root_pos[2] - 0.35, abs=1e-9)
    assert np.allclose(after.root_pos[:2], before.root_pos[:2], atol=1e-9)
    assert np.abs(after.positions[FEET] - before.positions[FEET]).max() < 1e-3  # planted, flat: toes too
    assert np.allclose(in_pelvis_frame(after)[UPPER], in_pelvis_frame(before)[UPPER], atol=1e-9)
    assert np.array_equal(after.latent, before.latent)
    for side in "lr":  # the knees bend forward, in front of the line from hip to ankle
        hip, knee, ankle = after.positions[[J[side + "hip"], J[side + "knee"], J[side + "ankle"]]]
        assert (knee - (hip + ankle) / 2) @ FORWARD > 0.2
    offsets = m.character.skeleton.offsets
    assert np.allclose(fk(after.local_rot, after.root_pos, offsets)[0], after.positions, atol=1e-9)
    root = m.targets["root"]
    assert root.pelvis_only and np.allclose(root.position, after.root_pos)


def test_the_drag_is_one_undo_step_that_restores_exactly(session):
    before = session.state()
    squat(session, 0.3)
    assert session.history.undo_text() == "move pelvis" and session.history.count() == 1
    session.undo()
    assert np.array_equal(session.pose.positions, before.pose.positions)
    assert np.array_equal(session.pose.local_rot, before.pose.local_rot)
    assert session.targets == {}
    session.redo()
    assert session.targets["root"].pelvis_only


def test_a_reachable_wrist_target_is_kept_and_a_plain_hips_drag_clears_the_flag(session):
    m = session.mode
    wrist = m.pose.positions[J["lwrist"]] + [0.0, -0.15, 0.1]
    for k in range(1, 6):
        session.drag_joint("lwrist", m.pose.positions[J["lwrist"]] + (wrist - m.pose.positions[J["lwrist"]]) * k / 5)
    feet = m.pose.positions[FEET].copy()
    squat(session, 0.1)
    assert np.linalg.norm(m.pose.positions[J["lwrist"]] - m.targets["lwrist"].position) < 1e-3
    assert np.abs(m.pose.positions[FEET] - feet).max() < 1e-3
    session.drag_joint("root", session.hips_handle() + [0.0, 0.0, -0.02])  # without Shift
    assert not m.targets["root"].pelvis_only


def test_a_pelvis_only_key_round_trips_and_bakes_to_the_same_pose(session, vae, tmp_path):
    m = session.mode
    for _ in range(5):  # a wrist dragged first: its latent's feet are not where the feet stand
        session.drag_joint("lwrist", m.pose.positions[J["lwrist"]] + np.array([0.0, -0.06, 0.04]))
    squat(session, 0.3, back=0.05)
    shown = m.pose
    session.add_key(0)
    session.set_length(1)
    save_authoring(tmp_path / "s.json", session.scene)
    scene = load_authoring(tmp_path / "s.json")
    key = scene.keys[0]
    assert key.targets["root"].pelvis_only and set(key.feet) == {"lankle", "ltoe", "rankle", "rtoe"}
    motion = bake(scene, vae).motion
    baked = fk(motion.local_rot[0], motion.root_pos[0], motion.skeleton.offsets)[0]
    assert np.abs(baked[FEET] - shown.positions[FEET]).max() < 2e-3
    assert np.abs(baked - shown.positions).max() < 5e-3
    assert np.allclose(motion.root_pos[0], shown.root_pos, atol=1e-6)


def test_the_flag_is_written_only_when_set_and_a_misspelt_one_is_refused(session):
    squat(session, 0.2)
    session.add_key(0)
    doc = authoring_to_dict(session.scene)
    assert doc["keys"][0]["targets"]["root"]["pelvis_only"] is True
    assert authoring_from_dict(doc, "s.json").keys[0].targets["root"].pelvis_only
    doc["keys"][0]["targets"]["root"]["pelvis_onyl"] = doc["keys"][0]["targets"]["root"].pop("pelvis_only")
    with pytest.raises(
        UserError, match=r"s.json: keys\[0\]: targets: root: .*'pelvis_onyl' \(did you mean 'pelvis_only'\?\)"
    ):
        authoring_from_dict(doc, "s.json")
    doc["keys"][0]["targets"]["root"]["pelvis_only"] = doc["keys"][0]["targets"]["root"].pop("pelvis_onyl")
    doc["keys"][0]["feet"]["ltoes"] = doc["keys"][0]["feet"].pop("ltoe")
    with pytest.raises(UserError, match=r"'ltoes' \(did you mean 'ltoe'\?\)"):
        authoring_from_dict(doc, "s.json")
    with pytest.raises(UserError, match="root's target only"):
        JointTarget("lwrist", [0, 0, 1], pelvis_only=True)
    with pytest.raises(UserError, match="true or false"):
        authoring_from_dict(
            {
                "format": "dragposer-scene",
                "version": 2,
                "keys": [{"frame": 0, "targets": {"root": {"position": [0, 0, 0.7], "pelvis_only": 1}}}],
            },
            "s.json",
        )


def test_a_pelvis_dragged_past_the_legs_reach_stops_with_them_nearly_straight(session):
    m = session.mode
    feet = m.pose.positions[FEET].copy()
    session.drag_pelvis(session.hips_handle() + [0.0, 0.0, 0.3])
    assert m.pose.root_pos[2] < m.standing_root + 0.05
    assert np.abs(m.pose.positions[FEET] - feet).max() < 1e-3


def test_in_betweens_next_to_a_pelvis_only_key_keep_the_feet_planted(session):
    """Between a standing key and a pelvis-only squat the pelvis goes down smoothly over
    the planted feet (the in-betweens stood at full height and snapped onto the squat)."""
    session.set_length(26)
    feet = session.pose.positions[FEET].copy()
    session.add_key(0)
    squat(session, 0.35, back=0.1)
    session.add_key(20)
    motion = session.bake_now().motion
    positions = np.stack([fk(motion.local_rot[f], motion.root_pos[f], motion.skeleton.offsets)[0] for f in range(26)])
    assert np.abs(positions[:, FEET] - feet).max() < 1e-3
    assert np.all(np.diff(motion.root_pos[:, 2]) < 1e-9) and motion.root_pos[10, 2] < motion.root_pos[0, 2] - 0.1
    assert np.abs(positions[21:] - positions[20]).max() < 0.01  # after the last key the squat is held
    assert np.linalg.norm(np.diff(positions, axis=0), axis=2).max() < 0.04  # no snap onto the key
