"""A pin on a joint that a target also holds, in the pose window's model: the pin wins on
its frames as it does in the bake (:func:`engine.authoring.pins.pinned_targets`), and a
drag of the pinned joint moves the pin with the target. Kept as a term (weight 30)
against the target, the pin pulled the latent's wrist towards it while the exact limb
step put the wrist on the dragged target: the trunk bent for a wrist that stayed put."""

from __future__ import annotations

import numpy as np

from engine import skeleton as sk
from engine.authoring.motion_paths import keyed_paths
from engine.authoring.pose_metrics import trunk_tilt_deg
from engine.authoring.pose_mode import PoseMode
from engine.authoring.session import AuthoringSession
from engine.kinematics.fk import fk

J = sk.JOINT_INDEX


def drag(s: AuthoringSession, joint: str, to: np.ndarray, events: int = 10) -> None:
    start = s.mode.pose.positions[J[joint]].copy()
    for k in range(1, events + 1):
        s.drag_joint(joint, start + (to - start) * k / events)


def test_a_pin_wins_over_the_target_of_its_joint_without_bending_the_trunk(vae):
    s = AuthoringSession(PoseMode(vae, 1.75))
    wrist = s.mode.pose.positions[J["lwrist"]].copy()
    upright = trunk_tilt_deg(s.mode.pose.positions)
    drag(s, "lwrist", wrist + [0.0, -0.15, 0.25])  # the target: hand forward and up
    place = wrist + [0.05, -0.1, 0.0]  # the pin: lower and nearer
    s.add_constraint("pin", joint="lwrist", position=place)
    p = s.mode.pose.positions
    assert np.linalg.norm(p[J["lwrist"]] - place) < 0.01
    np.testing.assert_allclose(s.mode.aimed["lwrist"].position, place)
    assert trunk_tilt_deg(p) < upright + 10.0


def test_a_drag_of_a_pinned_joint_moves_the_pin_with_it_in_one_step(vae):
    free = AuthoringSession(PoseMode(vae, 1.75))
    s = AuthoringSession(PoseMode(vae, 1.75))
    wrist = s.mode.pose.positions[J["lwrist"]].copy()
    s.add_constraint("pin", joint="lwrist", position=wrist)
    to = wrist + [0.0, -0.25, 0.3]
    drag(free, "lwrist", to)
    drag(s, "lwrist", to)
    (pin,) = s.mode.constraints
    np.testing.assert_allclose(pin.position, to)
    p = s.mode.pose.positions
    assert np.linalg.norm(p[J["lwrist"]] - to) < 0.01
    # the pinned drag poses the body as the same drag without the pin does
    assert abs(trunk_tilt_deg(p) - trunk_tilt_deg(free.mode.pose.positions)) < 3.0
    assert np.abs(p - free.mode.pose.positions).max() < 0.05
    assert s.holding_pin("lwrist") is pin
    s.undo()  # the drag is one step: the pin back where it was, with the target
    np.testing.assert_allclose(s.mode.constraints[0].position, wrist)
    assert "lwrist" not in s.mode.targets


def test_a_pin_outside_the_frame_leaves_a_drag_alone(vae):
    s = AuthoringSession(PoseMode(vae, 1.75))
    wrist = s.mode.pose.positions[J["lwrist"]].copy()
    s.add_constraint("pin", joint="lwrist", position=wrist, frames=(20, 30), blend_in=5)
    drag(s, "lwrist", wrist + [0.0, -0.2, 0.2])
    np.testing.assert_allclose(s.mode.constraints[0].position, wrist)


def test_the_path_before_the_bake_takes_the_pins_as_the_bake_does(vae):
    """The motion path drawn before the bake (the keys' latents interpolated, the limbs
    on the targets) puts the wrist where the bake will: on the pin over its frames, and
    the key inside its range holding the pin's place, not the key's target."""
    s = AuthoringSession(PoseMode(vae, 1.75))
    wrist = s.mode.pose.positions[J["lwrist"]].copy()
    drag(s, "lwrist", wrist + [0.03, 0.0, 0.05])
    s.add_key(0)
    s.frame = 40
    drag(s, "lwrist", wrist + [0.13, 0.0, 0.35])
    s.add_key(40)
    place = s.mode.pose.positions[J["lwrist"]] + [-0.1, -0.1, -0.2]
    s.add_constraint("pin", joint="lwrist", position=place, frames=(30, 40), blend_in=10)
    paths = keyed_paths(s.mode.character, s.keys, s.animation.interpolation, s.scene.constraints)
    assert paths is not None
    np.testing.assert_allclose(paths.at("lwrist", 40), place, atol=1e-6)
    np.testing.assert_allclose(paths.at("lwrist", 35), place, atol=1e-6)
    baked = s.bake_now().motion
    bake_wrist = fk(baked.local_rot, baked.root_pos, baked.skeleton.offsets)[0][:41, J["lwrist"]]
    assert np.linalg.norm(paths.line("lwrist") - bake_wrist, axis=1).max() < 0.01


def test_a_pin_on_a_planted_ankle_holds_it_where_the_pin_is_moved(vae):
    """A planted foot's ankle is held where it stood; a pin put on it and moved wins there
    too (as a pin wins over a target), so the ankle goes where the pin handle is dragged."""
    s = AuthoringSession(PoseMode(vae, 1.75))
    ankle = s.mode.pose.positions[J["lankle"]].copy()
    s.add_constraint("pin", joint="lankle", position=ankle)
    (pin,) = s.mode.constraints
    place = ankle + [0.0, -0.06, 0.0]  # 6 cm forward along the floor
    s.update_constraint(pin.name, {"position": place})
    assert np.linalg.norm(s.mode.pose.positions[J["lankle"]] - place) < 0.01


def test_a_blending_pin_on_a_planted_ankle_aims_it_part_way(vae):
    """On a frame of the pin's blend-in the planted ankle is aimed part of the way to the pin,
    by the pin's activity there, as a target is (not all the way)."""
    s = AuthoringSession(PoseMode(vae, 1.75))
    ankle = s.mode.pose.positions[J["lankle"]].copy()
    place = ankle + [0.0, -0.06, 0.0]
    s.add_constraint("pin", joint="lankle", position=place, frames=(4, 30), blend_in=8)
    (pin,) = s.mode.constraints
    a = pin.activity(s.mode.frame)
    assert 0.0 < a < 1.0
    (foot,) = [t for t in s.mode._inputs()[0] if t.name == "target:lankle"]
    np.testing.assert_allclose(foot.position, (1.0 - a) * ankle + a * place, atol=1e-9)


def lower_pelvis_alone(s: AuthoringSession, down: float, events: int = 10) -> None:
    start = s.hips_handle()
    for k in range(1, events + 1):
        s.drag_pelvis(start + [0.0, 0.0, -down * k / events])


def test_a_pin_on_a_planted_ankle_holds_it_under_a_pelvis_only_target(vae):
    """With the pelvis moved alone (Shift + drag on the hips) a pin on a planted ankle
    wins over its planting as it does standing: the leg reaches the pin, and the latent,
    which solves the body where it stood, aims the ankle at the pin moved by the pelvis's
    shift, as it aims the user's targets."""
    s = AuthoringSession(PoseMode(vae, 1.75))
    p0 = s.mode.pose.positions.copy()
    lower_pelvis_alone(s, 0.25)
    place = p0[J["lankle"]] + [0.0, -0.08, 0.0]  # 8 cm forward along the floor
    s.add_constraint("pin", joint="lankle", position=place)
    p = s.mode.pose.positions
    assert np.linalg.norm(p[J["lankle"]] - place) < 1e-3
    assert p[0, 2] < p0[0, 2] - 0.2, "the pelvis stays down"
    assert np.linalg.norm(p[J["rankle"]] - p0[J["rankle"]]) < 1e-6, "the other foot stays planted"
    assert p[J["ltoe"], 2] < p0[J["ltoe"], 2] + 0.02, "the pinned foot's toe stays down"
    pelvis = s.mode.pelvis_target()
    assert pelvis is not None
    shift = s.mode.pose.decoded[0] - pelvis.position
    (foot,) = [t for t in s.mode._inputs()[0] if t.name == "target:lankle"]
    np.testing.assert_allclose(foot.position, place + shift, atol=1e-9)
    s.settle()
    assert np.linalg.norm(s.mode.pose.positions[J["lankle"]] - place) < 1e-3
