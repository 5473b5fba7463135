"""A pin against a target in the pose window, as in the bake: on the pin's frames the pin
wins over its joint's target (the target spheres show where the solve aims, blended in
and out over the pin's blends), and a drag of the pinned joint moves the pin with it,
the status bar naming the pin (real clicks on the Constraints dock, real mouse drags).
Kept as a term (weight 30) against the dragged target, the pin pulled the latent's
wrist back towards it while the exact limb step put the wrist on the target, and the
in-between's sphere sat on the keys' target, off the pinned wrist."""

from __future__ import annotations

import numpy as np
import pytest

from engine import skeleton as sk
from engine.kinematics.fk import fk
from tests.app.gui_helpers import add_wrist_pin, mouse_drag, pixel_of, scrub

pytestmark = pytest.mark.gui

J = sk.JOINT_INDEX


def sphere_of(w, joint: str) -> np.ndarray:
    s = w.viewport.sensors
    return s.positions[list(s.joints).index(joint)]


def test_a_drag_of_a_pinned_wrist_moves_the_pin_and_says_so(pose_window):
    """A pin blending in on frame 26 holds the wrist part of the way from its target to
    the pin's place (its handle is there, off the wrist, so a press on the wrist grabs
    the wrist); the wrist dragged goes where it is dragged, the pin with it."""
    w = pose_window
    v = w.viewport
    v.set_camera("front", w.hips())
    v.plotter.render()
    scrub(w, 26)
    x, y = pixel_of(v, w.mode.pose.positions[J["lwrist"]])
    mouse_drag(v, (x, y), (x + 30, y + 60), steps=6)  # a target on the wrist
    target = w.mode.targets["lwrist"].position.copy()
    pin = add_wrist_pin(w)
    place = target + [0.1, -0.1, -0.25]
    w.session.update_constraint(pin.name, {"position": place, "frames": (30, 40), "blend_in": 10})
    a = w.mode.constraints[0].activity(26)
    assert 0.2 < a < 0.9
    wrist = w.mode.pose.positions[J["lwrist"]].copy()
    np.testing.assert_allclose(sphere_of(w, "lwrist"), (1 - a) * target + a * place, atol=1e-9)
    assert np.linalg.norm(wrist - sphere_of(w, "lwrist")) < 0.01
    messages = []
    w.statusBar().messageChanged.connect(lambda m: messages.append(m))
    v.plotter.render()
    x, y = pixel_of(v, wrist)
    mouse_drag(v, (x, y), (x - 40, y + 50), steps=8)
    assert w.undo.undo_text() == "move target lwrist"
    (pin,) = w.mode.constraints
    moved = w.mode.targets["lwrist"].position
    assert np.linalg.norm(moved - target) > 0.05
    np.testing.assert_allclose(pin.position, moved, atol=1e-9)  # the pin went with the target
    p = w.mode.pose.positions
    assert np.linalg.norm(p[J["lwrist"]] - moved) < 0.01
    np.testing.assert_allclose(sphere_of(w, "lwrist"), moved, atol=1e-9)
    assert any(repr(pin.name) in m and "moves the pin" in m for m in messages), messages
    w.undo_step()  # the drag is one step: the pin and the target back
    np.testing.assert_allclose(w.mode.constraints[0].position, place, atol=1e-9)
    np.testing.assert_allclose(w.mode.targets["lwrist"].position, target, atol=1e-9)


def test_the_in_between_shows_the_target_the_pin_blends_in(pose_window):
    """Keys at 0 and 40 (the wrist dragged on both), a pin for frames 30-40 blending in
    from frame 20: at frame 26 the wrist's sphere is the keys' target moved towards the
    pin by the pin's activity there, and the baked wrist is on it."""
    w = pose_window
    v = w.viewport
    v.set_camera("front", w.hips())
    v.plotter.render()
    x, y = pixel_of(v, w.mode.pose.positions[J["lwrist"]])
    mouse_drag(v, (x, y), (x + 20, y + 30), steps=6)
    w.keys.add.click()
    scrub(w, 40)
    x, y = pixel_of(v, w.mode.pose.positions[J["lwrist"]])
    mouse_drag(v, (x, y), (x + 50, y + 90), steps=6)
    w.keys.add.click()
    assert [k.frame for k in w.scene.keys] == [0, 40]
    held = w.mode.pose.positions[J["lwrist"]].copy()
    place = held + [-0.1, -0.1, -0.2]  # lower and nearer, within the arm's reach
    w.session.add_constraint("pin", joint="lwrist", position=place, frames=(30, 40), blend_in=10)
    (pin,) = w.mode.constraints
    scrub(w, 26)
    assert w.frame == 26
    a = pin.activity(26)
    assert 0.2 < a < 0.9
    # the keys' targets interpolated there, the key at 40 holding the pin's place (it is
    # inside the pin's range: the bake poses it there and the in-betweens aim at it)
    keyed_target = w.mode.targets["lwrist"].position
    blended = (1.0 - a) * keyed_target + a * place
    np.testing.assert_allclose(sphere_of(w, "lwrist"), blended, atol=1e-9)
    assert np.linalg.norm(w.mode.pose.positions[J["lwrist"]] - blended) < 0.01
    assert w.session.unkeyed_edit() is False
    # a key added there bakes the frame as it was shown (its targets are pinned once, not twice)
    before = fk(
        w.session.baked.motion.local_rot, w.session.baked.motion.root_pos, w.session.baked.motion.skeleton.offsets
    )
    w.keys.add.click()
    scrub(w, 30)
    after = fk(
        w.session.baked.motion.local_rot, w.session.baked.motion.root_pos, w.session.baked.motion.skeleton.offsets
    )
    assert np.abs(after[0][26] - before[0][26]).max() < 0.02  # as a key added on any in-between


def test_a_press_on_a_joint_left_on_its_pin_outside_the_pin_s_frames_drags_the_joint(pose_window):
    """A pin for frames 20-30 put where the wrist hangs: on frame 50, where it does not
    act, the wrist sits under the pin's handle, and a drag of the wrist gives the wrist a
    target and leaves the pin where it was (found with xdotool: the drag moved the pin,
    which then held the wrist over frames 20-30 where the drag ended). On frame 25 the
    same press still grabs the pin's handle."""
    w = pose_window
    v = w.viewport
    v.set_camera("front", w.hips())
    v.plotter.render()
    scrub(w, 50)
    pin = add_wrist_pin(w)
    w.session.update_constraint(pin.name, {"frames": (20, 30)})
    (pin,) = w.mode.constraints
    place = pin.position.copy()
    wrist = w.mode.pose.positions[J["lwrist"]].copy()
    np.testing.assert_allclose(place, wrist, atol=1e-6)
    v.plotter.render()
    x, y = pixel_of(v, wrist)
    mouse_drag(v, (x, y), (x + 40, y - 60), steps=8)
    assert w.undo.undo_text() == "move target lwrist"
    np.testing.assert_allclose(w.mode.constraints[0].position, place, atol=1e-9)
    assert np.linalg.norm(w.mode.pose.positions[J["lwrist"]] - wrist) > 0.1
    w.undo_step()
    scrub(w, 25)
    v.plotter.render()
    x, y = pixel_of(v, w.mode.pose.positions[J["lwrist"]])
    mouse_drag(v, (x, y), (x + 40, y - 60), steps=8)
    assert np.linalg.norm(w.mode.constraints[0].position - place) > 0.05
