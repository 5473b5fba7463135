"""The angle of a ring turn is read out while the ring is dragged (real mouse events):
a user asked for a head turned 60 degrees has a number to stop at. The ring turns by
whole degrees, and with Ctrl held by 5-degree steps, so 60 is reached exactly: seen from
above a head's rings span a few dozen pixels, about 2.5 degrees a pixel."""

from __future__ import annotations

import re

import numpy as np
import pytest

from engine import skeleton as sk
from engine.kinematics import quat_np as QN
from tests.app.gui_helpers import mouse_drag, mouse_move, mouse_press, mouse_release, pixel_of
from widgets.viewport.rings import AXES, circle

pytestmark = pytest.mark.gui
HEAD = sk.JOINT_INDEX["upperneck"]


def head_selected_from_above(w):
    """The top view, the head clicked (its rings show); the head's world rotation."""
    w.viewport.set_camera("top", w.hips())
    w.viewport.plotter.render()
    x, y = pixel_of(w.viewport, w.mode.pose.positions[HEAD])
    mouse_drag(w.viewport, (x, y), (x, y), steps=1)
    assert w.selected == "upperneck"
    return w.turns.world_rotation("upperneck")


def turned_deg(w, before) -> float:
    """Degrees the head's rotation target is turned from ``before``."""
    turn = QN.mul(w.mode.targets["upperneck"].rotation, QN.conjugate(before))
    return float(np.degrees(2 * np.arccos(min(1.0, abs(turn[0])))))


def readout_deg(w) -> float | None:
    """The angle the status bar reads for the head's turn, or None."""
    m = re.search(r"Turn upperneck .*: ([+-]\d+) deg", w.statusBar().currentMessage())
    return float(m.group(1)) if m else None


def ring_drag(w, to_deg: float, ctrl: bool = False) -> None:
    """Drag the head's blue ring from its 0-degree point to ``to_deg`` on the ring (the
    pixels rounded, as a hand's), counter-clockwise seen from above."""
    rings = w.viewport.rings
    w.viewport.plotter.render()
    ring = circle(rings.center, AXES[2], rings.radius, 3600)
    start = np.round(pixel_of(w.viewport, ring[0]))
    end = np.round(pixel_of(w.viewport, ring[int(round(10 * to_deg)) % 3600]))
    mouse_drag(w.viewport, tuple(start), tuple(end), steps=12, ctrl=ctrl)


def turn_until_it_reads(w, reads: float, ctrl: bool, out: float) -> list[float]:
    """A user's turn: press the head's blue ring at its 0-degree point, go round a circle
    ``out`` times the ring's radius (whole pixels) and let go where the status bar first
    reads ``reads`` degrees; the readouts seen on the way."""
    rings = w.viewport.rings
    w.viewport.plotter.render()
    start = tuple(np.round(pixel_of(w.viewport, circle(rings.center, AXES[2], rings.radius, 360)[0])))
    path = circle(rings.center, AXES[2], out * rings.radius, 1440)[: 4 * 90]  # every quarter degree to 90
    mouse_press(w.viewport, start, ctrl)
    seen, at = [], start
    for p in path:
        px = tuple(np.round(pixel_of(w.viewport, p)))
        if px == at:
            continue
        at = px
        mouse_move(w.viewport, at, ctrl)
        seen.append(readout_deg(w))
        if seen[-1] == reads:
            break
    mouse_release(w.viewport, at, ctrl)
    return seen


@pytest.mark.parametrize("aim", [57.0, 62.3, 64.6])
def test_a_ring_turns_by_whole_degrees(pose_window, aim):
    w = pose_window
    before = head_selected_from_above(w)
    ring_drag(w, aim)
    turned = turned_deg(w, before)
    assert turned == pytest.approx(round(turned), abs=1e-3), f"{turned:.4f} deg is not a whole number"
    assert turned == pytest.approx(aim, abs=4.0)
    assert readout_deg(w) == round(turned)


def test_a_ring_turn_stops_at_60_where_the_status_bar_reads_60(pose_window):
    """Three ring radii out from the head, under a degree a pixel: the readout passes
    +60 and the head is turned exactly that."""
    w = pose_window
    before = head_selected_from_above(w)
    seen = turn_until_it_reads(w, 60.0, ctrl=False, out=3.0)
    assert seen[-1] == 60.0, seen
    assert turned_deg(w, before) == pytest.approx(60.0, abs=1e-3)


def test_with_ctrl_held_a_ring_turns_by_5_degrees_and_reaches_60_on_the_ring(pose_window):
    """On the ring itself (about 2.5 degrees a pixel) the 5-degree steps read +60 on the
    way; let go there, the head is turned exactly 60 degrees."""
    w = pose_window
    before = head_selected_from_above(w)
    seen = turn_until_it_reads(w, 60.0, ctrl=True, out=1.0)
    assert seen[-1] == 60.0 and len(set(seen)) > 5 and all(r % 5 == 0 for r in seen), seen
    assert turned_deg(w, before) == pytest.approx(60.0, abs=1e-3)
    assert "+60 deg (to its left)" in w.statusBar().currentMessage()


def test_the_status_bar_reads_the_angle_of_a_ring_turn_while_it_is_dragged(pose_window):
    w = pose_window
    before = head_selected_from_above(w)
    rings = w.viewport.rings
    ring = circle(rings.center, AXES[2], rings.radius, 72)  # 5 degrees apart, counter-clockwise from above
    w.viewport.plotter.render()
    path = [pixel_of(w.viewport, ring[k]) for k in (0, 12)]  # 0 -> 60 degrees
    seen: list[str] = []
    mouse_drag(w.viewport, path[0], path[1], steps=12, on_move=lambda: seen.append(w.statusBar().currentMessage()))
    turned = turned_deg(w, before)
    message = w.statusBar().currentMessage()
    assert message.startswith("Turn upperneck about Z (blue ring): +") and "(to its left)" in message
    assert message.endswith("Ctrl: 5-deg steps")
    shown = float(re.search(r"([+-]\d+) deg", message).group(1))
    assert shown == pytest.approx(turned, abs=1.0) and shown == pytest.approx(60.0, abs=3.0)
    assert len({m for m in seen if m.startswith("Turn upperneck")}) > 3, "the number follows the mouse"
