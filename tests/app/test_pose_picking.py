"""Real mouse presses in the pose window that several handles compete for: a target's
sphere inside its own rotation rings, and the hips dragged up and down (a squat)."""

from __future__ import annotations

import numpy as np
import pytest

from engine import skeleton as sk
from tests.app.gui_helpers import mouse_drag, pixel_of
from widgets.viewport.rings import RING_PICK_PX

pytestmark = pytest.mark.gui
LW = sk.JOINT_INDEX["lwrist"]


def test_a_press_on_a_target_inside_its_rings_drags_the_target(pose_window):
    """The wrist's rings show after a drag; the Z ring, seen almost edge-on from the
    home camera, crosses the wrist's sphere: a press there moves the target."""
    w = pose_window
    view = w.viewport
    view.plotter.render()
    x, y = pixel_of(view, w.mode.pose.positions[LW])
    mouse_drag(view, (x, y), (x - 30, y), steps=4)  # a target on the wrist; its rings show
    assert w.selected == "lwrist" and view.rings.visible and view.rings.shown == (0, 1, 2)
    placed = w.mode.targets["lwrist"].position.copy()
    view.plotter.render()
    x, y = pixel_of(view, placed)
    z_ring = view.joints._to_display(view.rings.meshes[2].points)
    assert np.linalg.norm(z_ring - [x, y], axis=1).min() < RING_PICK_PX, "the Z ring crosses the sphere's middle"
    far = z_ring[np.argmax(np.linalg.norm(z_ring - [x, y], axis=1))]
    assert view.rings.pick(view.joints._to_display, *far) is not None, "on its circle off the sphere, a ring is grabbed"
    mouse_drag(view, (x, y), (x, y + 40), steps=6)
    t = w.mode.targets["lwrist"]
    assert t.rotation is None, "no ring turned the wrist"
    assert t.position[2] - placed[2] > 0.1, "the target followed the mouse up"
    assert view.joints.ring is None and view.joints.target is None


def test_dragging_the_hips_down_squats_over_the_planted_feet(pose_window):
    """Two real drags of the hips straight down the screen, 15 cm each (the second
    starts on the hips, which the crouch's balance moved back, inside their own ring):
    the pelvis goes 30 cm down, the ankles stay where they stand, the knees bend, the
    body's place does not travel."""
    w = pose_window
    view = w.viewport
    feet = [sk.JOINT_INDEX[j] for j in ("lankle", "rankle")]
    knee, hip, ankle = (sk.JOINT_INDEX[j] for j in ("lknee", "lhip", "lankle"))
    before = w.mode.pose.positions.copy()
    for _ in range(2):
        view.plotter.render()
        hips = w.mode.pose.positions[0]
        start = pixel_of(view, hips)
        end = pixel_of(view, hips - [0.0, 0.0, 0.15])
        assert abs(end[0] - start[0]) < 1.0, "straight down the screen"
        mouse_drag(view, start, end, steps=6)
        assert w.selected == "root" and view.joints.ring is None
    after = w.mode.pose.positions
    assert before[0, 2] - after[0, 2] == pytest.approx(0.30, abs=0.015)
    place = w.mode.targets["root"].position
    assert np.linalg.norm(place[:2] - before[0, :2]) < 0.01, "the body stays where it stands"
    assert np.abs(after[feet] - before[feet]).max() < 0.005, "the ankles stay planted"
    u, v = after[hip] - after[knee], after[ankle] - after[knee]
    assert np.degrees(np.arccos(u @ v / np.linalg.norm(u) / np.linalg.norm(v))) < 120, "the knee bends"
    assert w.undo.undo_text() == "move body" and w.mode.targets["root"].position[2] < before[0, 2] - 0.25


@pytest.fixture
def crouching_window(qtbot, vae, monkeypatch):
    """A pose window whose pose mode crouches for every wrist reach below the arm hanging
    from the standing shoulder (``stoop_deg=0``): a hand on the knee crouches the body, so
    the hand comes down beside the hips."""
    from PyQt6.QtWidgets import QMessageBox

    from app.pose_window import PoseWindow
    from engine.authoring.pose_mode import PoseMode, PoseOptions
    from engine.authoring.session import AuthoringSession
    from tests.app.gui_helpers import close_now

    monkeypatch.setattr(QMessageBox, "question", lambda *a, **k: QMessageBox.StandardButton.Discard)
    options = PoseOptions(stoop_deg=0.0, crouch_share=0.5)
    w = PoseWindow(AuthoringSession(PoseMode(vae, 1.75, options=options)))
    w.resize(1000, 700)
    w.show()
    yield w
    close_now(w)


def test_the_hips_dragged_up_beside_a_wrist_s_rings_move_the_body_not_the_wrist(crouching_window):
    """From the front view the left wrist is dragged to the right knee (the body crouches
    with it, :func:`crouching_window`), then the hips are dragged up. The wrist stays
    selected, and its rings (12 cm) pass over the hips: a press on the hips' centre moves
    the body, it does not turn the wrist."""
    w = crouching_window
    view = w.viewport
    view.set_camera("front", w.hips())
    view.plotter.render()
    standing = w.mode.pose.positions.copy()
    mouse_drag(view, pixel_of(view, standing[LW]), pixel_of(view, standing[sk.JOINT_INDEX["rknee"]]), steps=10)
    crouched = w.mode.pose.positions.copy()
    assert w.selected == "lwrist" and crouched[0, 2] < standing[0, 2] - 0.2, "the reach bends the knees"
    view.plotter.render()
    start = pixel_of(view, crouched[0])
    assert view.rings.pick(view.joints._to_display, *start) is not None, "a ring of the wrist crosses the hips"
    mouse_drag(view, start, pixel_of(view, crouched[0] + [0.0, 0.0, 0.15]), steps=8)
    assert w.mode.targets["lwrist"].rotation is None, "the wrist was not turned"
    assert w.undo.undo_text() == "move body" and w.selected == "root"
    assert w.mode.targets["root"].position[2] == pytest.approx(crouched[0, 2] + 0.15, abs=0.01)
    assert w.mode.pose.positions[0, 2] > crouched[0, 2] + 0.1, "the pelvis went up"


def test_a_target_that_goes_away_during_its_drag_ends_the_drag(pose_window):
    """A target sphere is being dragged when the target is cleared (Clear all, an undo or a
    key change from the keyboard while the button is held): the rest of the drag moves
    nothing and raises nothing (the GUI monkey met a ValueError here)."""
    w = pose_window
    view = w.viewport
    view.plotter.render()
    x, y = pixel_of(view, w.mode.pose.positions[LW])
    mouse_drag(view, (x, y), (x - 30, y), steps=4)  # a target on the wrist
    view.plotter.render()
    x, y = pixel_of(view, w.mode.targets["lwrist"].position)
    moves = []

    def clear_on_second_move() -> None:
        moves.append(1)
        if len(moves) == 2:
            w.clear_all()

    mouse_drag(view, (x, y), (x, y + 40), steps=6, on_move=clear_on_second_move)
    assert "lwrist" not in w.mode.targets and view.joints.target is None
