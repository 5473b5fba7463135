"""Root motion: a pose moves and turns as a whole without changing its latent, and a bake
carries the keys' root positions and headings through the in-betweens into the motion."""

from __future__ import annotations

import numpy as np
import pytest

from engine.authoring.bake import bake
from engine.authoring.character import Character, heading_deg
from engine.authoring.document import AuthoringScene
from engine.authoring.keys import Animation, Key, interpolate
from engine.kinematics.fk import fk


def test_a_moved_and_turned_pose_is_the_same_pose_placed_elsewhere(vae):
    c = Character(vae, 1.8)
    pose = c.decode(c.mean_latent(), c.grounded((0.2, -0.1), 30.0))
    moved = pose.moved([0.5, 1.0, 0.0]).turned(90.0)
    assert np.array_equal(moved.latent, pose.latent)
    assert np.allclose(moved.root_pos, pose.root_pos + [0.5, 1.0, 0.0])
    assert np.allclose(fk(moved.local_rot, moved.root_pos, c.skeleton.offsets)[0], moved.positions, atol=1e-9)
    assert heading_deg(moved.local_rot[0]) - heading_deg(pose.local_rot[0]) == pytest.approx(90.0, abs=1e-6)
    # the bone lengths and the height above the floor do not change
    assert np.allclose(moved.positions[:, 2], pose.positions[:, 2])
    again = c.decode(c.mean_latent(), c.grounded(moved.root_pos[:2], 120.0))  # what a key at 120 degrees bakes
    assert np.allclose(again.positions, moved.positions, atol=1e-4)


def test_a_bake_interpolates_the_keys_root_and_heading(vae):
    c = Character(vae, 1.75)
    z = c.mean_latent()
    keys = [
        Key(0, latent=z, root=np.array([0.0, 0.0]), heading=0.0),
        Key(20, latent=z, root=np.array([0.8, -0.4]), heading=170.0),
        Key(40, latent=z, root=np.array([1.6, -0.4]), heading=-170.0),
    ]
    motion = bake(AuthoringScene(animation=Animation(30.0, 41, "cubic"), keys=keys, height=1.75), vae).motion
    root = motion.root_pos
    assert np.allclose(root[[0, 20, 40], :2], [[0, 0], [0.8, -0.4], [1.6, -0.4]], atol=1e-6)
    between = interpolate([0, 20, 40], [k.root for k in keys], 10, "cubic")  # (0.3, -0.175): the keys' spline
    assert np.allclose(root[10, :2], between, atol=1e-6) and 0.2 < root[10, 0] < 0.6
    assert np.all(np.diff(root[:, 0]) > -1e-6)  # travels forward throughout
    yaw = np.array([heading_deg(q) for q in motion.local_rot[:, 0]])
    turn = (yaw - yaw[0] + 180.0) % 360.0 - 180.0
    unwrapped = [np.array([h]) for h in (0.0, 170.0, 190.0)]
    assert turn[20] == pytest.approx(170.0, abs=1.0)
    assert turn[10] == pytest.approx(interpolate([0, 20, 40], unwrapped, 10, "cubic")[0], abs=1.0)
    steps = np.abs((np.diff(yaw) + 180.0) % 360.0 - 180.0)
    assert steps[20:].max() < 5.0  # 170 -> -170 turns the short way (20 degrees), not 340


def test_dragging_the_hips_down_squats_sideways_moves_and_back_up_stands(vae):
    from engine import skeleton as sk
    from engine.authoring.pose_mode import LOWEST_ROOT, SQUAT_FROM, PoseMode

    m = PoseMode(vae, 1.75)
    ankles = [sk.JOINT_INDEX["lankle"], sk.JOINT_INDEX["rankle"]]
    start = m.pose.positions.copy()
    standing = m.standing_root
    m.drag_hips(start[0] - [0.0, 0.0, SQUAT_FROM / 2])  # the jitter of a level drag
    assert m.targets == {} and m.pose.root_pos[2] == pytest.approx(standing)
    for k in range(1, 11):  # 30 cm down in ten drag events
        m.drag_hips(start[0] - [0.0, 0.0, 0.03 * k])
    assert standing - m.pose.root_pos[2] == pytest.approx(0.30, abs=0.015)
    assert np.abs(m.pose.positions[ankles] - start[ankles]).max() < 1e-3  # the planted feet stay
    assert np.allclose(m.hips_handle()[:2], start[0, :2], atol=1e-6)  # the body's place stays
    m.drag_hips(m.hips_handle() + [0.2, 0.0, 0.0])  # sideways while squatting: the body travels, still low
    assert m.targets["root"].position[0] == pytest.approx(start[0, 0] + 0.2)
    assert np.allclose(m.pose.positions[ankles, 0] - start[ankles, 0], 0.2, atol=1e-3)
    assert standing - m.pose.root_pos[2] > 0.25
    m.drag_hips(m.hips_handle() - [0.0, 0.0, 5.0])  # no lower than a deep squat
    assert m.targets["root"].position[2] == pytest.approx(LOWEST_ROOT * standing)
    m.drag_hips(m.hips_handle() + [0.0, 0.0, 5.0])  # back up: standing, the target gone
    assert "root" not in m.targets


def test_a_squat_keeps_the_weight_over_the_feet_and_a_second_drag_does_not_move_them(vae):
    """Hips dragged straight down 40 cm: the pelvis goes back as it goes down so the centre
    of mass stays over the middle of the planted feet (without the crouch balance it ends
    17 cm ahead of it, in front of the toes: a body on its toes); a second straight-down
    drag from the hips' handle leaves the feet where they are."""
    from engine import skeleton as sk
    from engine.authoring.pose_metrics import centre_of_mass
    from engine.authoring.pose_mode import PoseMode, PoseOptions

    ankles = [sk.JOINT_INDEX["lankle"], sk.JOINT_INDEX["rankle"]]

    def squat(options):
        m = PoseMode(vae, options=options)
        feet = np.mean([p[:2] for p in m.planted.values()], axis=0)
        start = m.hips_handle()
        for k in range(1, 21):
            m.drag_hips(start - [0.0, 0.0, 0.02 * k])
        return m, float(np.linalg.norm(centre_of_mass(m.pose.positions)[:2] - feet))

    m, off = squat(PoseOptions())
    assert off < 0.05
    assert squat(PoseOptions(crouch_balance=False))[1] > 0.12
    ankles_before = m.pose.positions[ankles].copy()
    start = m.hips_handle()
    for k in range(1, 6):
        m.drag_hips(start - [0.0, 0.0, 0.01 * k])
    assert np.abs(m.pose.positions[ankles] - ankles_before).max() < 1e-3


def test_hips_dragged_up_past_standing_after_a_reach_to_the_shin_stay_standing(vae):
    """A wrist put on the opposite shin (below what the stooping trunk reaches) crouches
    the body; the hips dragged back up to (and past) standing height hold the pelvis
    there, so the trunk bends over straight legs, instead of losing the target and
    crouching again for the reach. A hand on the knee stoops without a crouch, so there
    the hips dragged up lose their target and the hand stays on the knee."""
    from engine import skeleton as sk
    from engine.authoring.pose_drag import drag
    from engine.authoring.pose_mode import PoseMode

    for below_knee, crouches in ((0.2, True), (0.0, False)):
        m = PoseMode(vae, 1.75)
        standing = m.standing_root
        goal = m.pose.positions[sk.JOINT_INDEX["lknee"]] + [0.0, -0.08, -below_knee]
        drag(m, "rwrist", m.character.skeleton.offsets, position=goal, events=20)
        assert (standing - m.pose.root_pos[2] > 0.15) == crouches
        start = m.hips_handle()
        for k in range(1, 11):  # up to 10 cm past standing height in ten drag events
            m.drag_hips(start + [0.0, 0.0, (standing + 0.1 - start[2]) * k / 10])
        for _ in range(5):  # the drag goes on solving (as on the next mouse moves)
            m.solve()
        if crouches:
            assert m.targets["root"].position[2] == pytest.approx(standing)
            assert m.pose.root_pos[2] == pytest.approx(standing, abs=0.02)
        else:
            assert "root" not in m.targets
            assert np.linalg.norm(m.pose.positions[sk.JOINT_INDEX["rwrist"]] - goal) < 0.02


def test_hips_dragged_up_to_standing_with_a_reach_the_arm_makes_lose_their_target(vae):
    """A wrist target the standing arm reaches (30 cm forward) crouches nothing, so hips
    squatted and dragged back up release the pelvis as before."""
    from engine import skeleton as sk
    from engine.authoring.pose_mode import PoseMode

    m = PoseMode(vae, 1.75)
    start = m.pose.root_pos.copy()
    m.set_target("lwrist", m.pose.positions[sk.JOINT_INDEX["lwrist"]] + [0.0, -0.3, 0.0])
    for k in range(1, 6):
        m.drag_hips(start - [0.0, 0.0, 0.04 * k])
    assert "root" in m.targets
    m.drag_hips(m.hips_handle() + [0.0, 0.0, 1.0])
    assert "root" not in m.targets


def test_a_fast_squat_drag_reaches_its_depth_with_the_feet_flat(vae):
    """The hips dragged 30 cm down in one mouse move (a fast drag sends few events): the
    drag event's solve goes on for further rounds until the pelvis is at its height and
    the planted feet are back in place, so the toes stay down (one round left the left
    toe 4 cm up and the pelvis 4 cm high, the foot rolled back on its heel)."""
    from engine import skeleton as sk
    from engine.authoring.pose_mode import PoseMode

    m = PoseMode(vae, 1.87)
    start = m.pose.positions.copy()
    goal = m.hips_handle() - [0.0, 0.0, 0.30]
    m.drag_hips(goal)
    toes = [sk.JOINT_INDEX["ltoe"], sk.JOINT_INDEX["rtoe"]]
    assert m.pose.root_pos[2] == pytest.approx(goal[2], abs=0.01)
    assert np.abs(m.pose.positions[toes, 2] - start[toes, 2]).max() < 0.01
