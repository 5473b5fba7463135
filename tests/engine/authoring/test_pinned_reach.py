"""A wrist target the lowered pelvis takes out of the arm's reach (issue 50, defect 2):
the trunk leans to it, in the Shift drag of the pelvis alone and in the plain hips drag,
whose crouch balance would otherwise pull the body back, away from the hand."""

from __future__ import annotations

import numpy as np
import pytest

from engine import skeleton as sk
from engine.authoring.pose_metrics import check_pose
from engine.authoring.pose_mode import PoseMode

J = sk.JOINT_INDEX
#: The right wrist dragged forward and up, near the arm's full reach from the standing
#: shoulder (character frame: -Y forward, +Z up), metres.
REACH = np.array([0.0, -0.35, 0.15])


def _pinned_then_lowered(vae, how: str, down: float) -> tuple[PoseMode, np.ndarray, np.ndarray]:
    mode = PoseMode(vae, 1.75)
    start = mode.pose.positions.copy()
    goal = start[J["rwrist"]] + REACH
    for k in range(1, 21):
        mode.set_target("rwrist", start[J["rwrist"]] + REACH * k / 20)
        mode.solve()
    feet = mode.pose.positions[[J["lankle"], J["rankle"]]].copy()
    handle = mode.hips_handle()
    drag = mode.drag_pelvis if how == "pelvis" else mode.drag_hips
    for k in range(1, 9):
        drag(handle + np.array([0.0, 0.0, -down]) * k / 8)
    return mode, goal, feet


@pytest.mark.parametrize("how", ["pelvis", "hips"])
def test_a_pinned_hand_stays_on_its_target_as_the_pelvis_goes_down(vae, how):
    """Pinned 35 cm forward and 15 cm up, then the pelvis dragged 25 cm down (alone, or
    as a crouch): the hand stays within 1.5 cm of its target (2.7 and 10.4 cm off when
    the carried arm was left short and the crouch's balance took the hips 22 cm back),
    the ankles where they stood, the centre of mass over the feet."""
    mode, goal, feet = _pinned_then_lowered(vae, how, 0.25)
    gap = np.linalg.norm(mode.pose.positions[J["rwrist"]] - goal)
    assert gap < 0.015, f"the hand is {100 * gap:.1f} cm off its target"
    assert np.abs(mode.pose.positions[[J["lankle"], J["rankle"]]] - feet).max() < 1e-3
    check = check_pose(mode.pose.local_rot, mode.pose.root_pos, mode.character.skeleton.offsets)
    assert all(check.feet_down.values()) and check.balance_margin_cm > 0


@pytest.mark.parametrize("how", ["pelvis", "hips"])
def test_a_hand_the_deep_pelvis_takes_out_of_reach_ends_as_near_as_the_trunk_leans(vae, how):
    """The same hand, the pelvis 40 cm down: the trunk leans towards the hand and it ends
    within 8 cm (9.2 and 17.4 cm with the trunk carried upright or pulled back)."""
    mode, goal, _ = _pinned_then_lowered(vae, how, 0.40)
    gap = np.linalg.norm(mode.pose.positions[J["rwrist"]] - goal)
    assert gap < 0.08, f"the hand is {100 * gap:.1f} cm off its target"


def test_the_shoulder_is_pulled_to_a_hand_out_of_reach_under_a_pelvis_only_target(vae):
    """The stoop pull (``stoop_deg``) under a target on the root: a pelvis dragged alone
    25 cm down leaves the pinned hand beyond the carried arm, and the latent solve (in the
    standing body's frame) gets a pull on the right shoulder to within reach of the hand;
    a crouch target on the root (the plain hips drag) gets none."""
    mode = PoseMode(vae, 1.75)
    hand = mode.pose.positions[J["rwrist"]] + REACH
    mode.set_target("rwrist", hand)
    lowered = mode.pose.root_pos - np.array([0.0, 0.0, 0.25])
    mode.set_target("root", lowered, pelvis_only=True)
    mode.pose = mode.pelvis_step(mode.pose)
    where = mode.pose.decoded[0].copy()
    pulls = mode._stoop_terms(where)
    assert [t.joint for t in pulls] == ["rshoulder"]
    reach = 0.95 * (
        np.linalg.norm(mode.pose.positions[J["relbow"]] - mode.pose.positions[J["rshoulder"]])
        + np.linalg.norm(mode.pose.positions[J["rwrist"]] - mode.pose.positions[J["relbow"]])
    )
    shift = mode.pose.decoded[0] - lowered  # the standing body's frame, where the latent solves
    assert np.linalg.norm(pulls[0].position - (hand + shift)) == pytest.approx(reach, abs=1e-6)
    mode.set_target("root", lowered, pelvis_only=False)
    assert mode._stoop_terms(mode.pose.root_pos) == []
