"""Dragging in the 3D view: Ctrl + left-drag on a joint of the reconstruction (a pin),
plain left-drag on a tracker's target sphere (its offset); selecting a joint.

The press is tested against the joints' screen positions (within ``PICK_RADIUS_PX``) or
against the targets' on-screen spheres (:meth:`SensorMarkers.pick`); on a hit the camera
interaction is suspended until release, and every mouse move is turned into a world
position: the mouse ray intersected with the plane through the grabbed point that faces
the camera (in a view that looks along a world axis, within :data:`AXIS_SNAP_DEG`, the
plane normal to that axis: the front view moves a joint at its own depth exactly). Off
every joint and target, the camera behaves as usual.

A press that grabs a joint or a target selects it (``on_select``); so does a click (a
press and a release :data:`CLICK_PX` apart at most) on a joint where a press turns the
camera (the studio without Ctrl).
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np
import pyvista as pv

from engine.skeleton import JOINT_NAMES

PICK_RADIUS_PX = 14.0
#: Joints whose centres lie this near a press (pixels: the radius of the balls the
#: skeleton draws, ``widgets.viewport.skeleton``'s 12-pixel points) are all under the
#: cursor; the press grabs the one drawn in front.
DRAWN_RADIUS_PX = 6.0
#: A Shift press this near (pixels) :attr:`JointDragger.shift_grabs` grabs it before
#: anything else: the hips sit among the hip and back joints, a few pixels apart.
SHIFT_PICK_RADIUS_PX = 28.0
#: Priority of the dragger's press observer on the interactor: below the gizmos' point
#: handles (:data:`widgets.viewport.gizmo_adapters.HANDLE_PRIORITY`), so a pin's handle
#: on a joint is its own, above their boxes (``BOX_PRIORITY``) and the camera style.
PRESS_PRIORITY = 0.55
#: An upright joint (:attr:`JointDragger.upright`) moves on a level-normal plane while
#: the view's direction is within asin(0.87) = 60 degrees of level.
UPRIGHT_STEEPEST = 0.87
#: A view direction within this many degrees of a world axis drags on the plane normal
#: to that axis (the camera presets look along an axis but from a little above).
AXIS_SNAP_DEG = 8.0
#: A press and a release at most this far apart (pixels) are a click.
CLICK_PX = 3.0


class JointDragger:
    """Emits ``on_drag(joint name, world position (3,) metres)`` while a joint is dragged;
    a target of ``sensors`` (:class:`widgets.viewport.sensors.SensorMarkers`), when given,
    is dragged through its own ``begin_drag``/``drag``/``end_drag``."""

    def __init__(
        self,
        plotter: pv.Plotter,
        on_drag: Callable[[str, np.ndarray], None],
        sensors: Any = None,
        rings: Any = None,
        on_turn: Callable[[int, float, bool], None] | None = None,
        on_select: Callable[[str], None] | None = None,
    ) -> None:
        self._plotter = plotter
        self._on_drag = on_drag
        self._on_select = on_select
        #: Where a dragged joint or target goes: ``place(name, point on the drag plane,
        #: point pressed, a point of the line it may move along and that line's direction
        #: (the mouse ray's), plane normal) -> point (3,)`` (the pose window picks a
        #: wrist's depth by the drag's length); None: the plane's point.
        self.place: Callable[..., np.ndarray] | None = None
        self._click: tuple[float, float] | None = None  # a press the camera took, until its release
        self._sensors = sensors
        #: Rotation rings (:class:`widgets.viewport.rings.RotationRings`), grabbed before
        #: anything else; ``on_turn(axis, radians swept, first)`` while one is dragged.
        self._rings = rings
        self._on_turn = on_turn
        self.ring: int | None = None
        self.positions: np.ndarray | None = None
        self.joint: int | None = None
        self.target: str | None = None  # the tracker target being dragged
        #: A press without Ctrl grabs a joint too when no target is under it (the pose
        #: window: the studio keeps a plain press on the body for the camera).
        self.plain_press_grabs_joints = False
        #: Joints (and targets, by joint) dragged on an upright plane facing the camera
        #: instead of the camera-facing one, so that a mouse moved up or down the screen
        #: moves them straight up or down (the pose window's hips: a squat) while a
        #: sideways move stays level (see :meth:`drag_normal`).
        self.upright: frozenset[str] = frozenset()
        #: Where a drag of the named joint starts when that is not the joint itself:
        #: ``drag_origin(name)`` gives it (3,) metres, or None for the joint (the pose
        #: window's hips move the body's place, its handle, which a balanced crouch
        #: leaves in front of the pelvis). A drag sends that point moved by the cursor's
        #: way on the drag plane.
        self.drag_origin: Callable[[str], np.ndarray | None] | None = None
        #: A joint that a press with Shift grabs from up to :data:`SHIFT_PICK_RADIUS_PX`
        #: away, before rings, targets and nearer joints (the pose window's hips: Shift +
        #: drag moves the pelvis alone); None: Shift picks as a plain press.
        self.shift_grabs: str | None = None
        #: Joints whose press grabs another joint instead: ``{pressed: grabbed}`` (the pose
        #: window's hip joints stand for the pelvis: they move only with it, and in the side
        #: view they are the balls where the legs meet the body, which a user takes for
        #: the hips; a target on one folds the legs under the body).
        self.stand_ins: dict[str, str] = {}
        self._origin = np.zeros(3)  # the grabbed thing's place: the drag plane goes through it
        self._base = np.zeros(3)  # what the drag moves: sent as _base + (hit - _grab)
        self._grab = np.zeros(3)  # the cursor's point on the drag plane at the press
        iren = plotter.iren.interactor
        self._style = iren.GetInteractorStyle()
        # The press is watched on the interactor between the gizmos' widgets (see
        # PRESS_PRIORITY) and the style, and aborted when taken: a target or a ring
        # inside an editable box is then grabbed before the box's faces, which cover it
        # on screen. A style observer on MouseMoveEvent replaces the style's handler
        # (VTK's HandleObservers rule), so mouse moves are forwarded explicitly when
        # nothing is held.
        self._commands = {}
        tag = iren.AddObserver("LeftButtonPressEvent", self._handle, PRESS_PRIORITY)
        self._commands["LeftButtonPressEvent"] = iren.GetCommand(tag)
        tag = self._style.AddObserver("MouseMoveEvent", self._handle, 10.0)
        self._commands["MouseMoveEvent"] = self._style.GetCommand(tag)
        # The release is watched on the interactor, ahead of every widget (they observe
        # it at priority 0.5): a VTK sphere widget that has never been grabbed takes the
        # first release it sees, and one made during a drag (the pin a Ctrl-drag creates)
        # would then leave the joint held, so every later mouse move dragged the pin.
        tag = iren.AddObserver("LeftButtonReleaseEvent", self._handle, 100.0)
        self._commands["LeftButtonReleaseEvent"] = iren.GetCommand(tag)
        # A press the camera took: the style grabs the interactor's focus until the
        # release, which then reaches the style alone; watched there (and passed on, as
        # the mouse moves are) to tell a click from a turn of the camera.
        self._style.AddObserver("LeftButtonReleaseEvent", self._camera_release, 10.0)

    def _take(self, event: str) -> None:
        self._commands[event].SetAbortFlag(1)

    def _handle(self, obj: object, event: str) -> None:
        iren = self._plotter.iren.interactor
        x, y = iren.GetEventPosition()
        if event == "LeftButtonPressEvent":
            self._click = None
            if iren.GetShiftKey() and self.press_shifted(x, y):
                self._take(event)
                self._select(self.shift_grabs)
            elif self.press_ring(x, y):
                self._take(event)
            elif self.press(x, y) if iren.GetControlKey() else self.press_plain(x, y):
                self._take(event)
                self._select(self.target if self.target is not None else JOINT_NAMES[self.joint])
            else:
                self._click = (x, y)
        elif event == "MouseMoveEvent":
            if self.ring is not None:
                coarse = bool(iren.GetControlKey())  # read from this move's own event
                self._on_turn(self.ring, self._rings.angle(self.ray(x, y), coarse), False)
            elif self.joint is not None or self.target is not None:
                self.move(x, y)
            else:
                self._style.OnMouseMove()
        elif event == "LeftButtonReleaseEvent" and (
            self.ring is not None or self.joint is not None or self.target is not None
        ):
            self.release()
            self._take(event)

    def _camera_release(self, obj: object, event: str) -> None:
        """The release of a press the camera took: a click on a joint selects it."""
        x, y = self._plotter.iren.interactor.GetEventPosition()
        click, self._click = self._click, None
        self._style.OnLeftButtonUp()
        if click is not None and np.hypot(x - click[0], y - click[1]) <= CLICK_PX:
            j = self.joint_at(x, y)
            if j is not None:
                self._select(JOINT_NAMES[j])

    def _select(self, name: str | None) -> None:
        if name is not None and self._on_select is not None:
            self._on_select(name)

    def press_ring(self, x: float, y: float) -> bool:
        """Grab the rotation ring under display pixel (x, y); True on a hit. A press
        nearer a joint's centre than the ring's circle is left to that joint where a press
        grabs joints: a wrist's rings (12 cm) brought down beside the hips cross them, and
        the hips dragged back up turned the wrist instead."""
        if self._rings is None or self._on_turn is None:
            return False
        axis = self._rings.pick(self._to_display, x, y)
        if axis is None:
            return False
        grabs_joints = self.plain_press_grabs_joints or self._plotter.iren.interactor.GetControlKey()
        near = self._nearest(x, y) if grabs_joints else None
        if near is not None and near[1] < self._rings.distance(self._to_display, axis, x, y):
            return False
        self.ring = axis
        self._rings.begin(axis, self.ray(x, y))
        self._on_turn(axis, 0.0, True)
        return True

    def _to_display(self, points: np.ndarray) -> np.ndarray:
        ren = self._plotter.renderer
        out = []
        for p in points:
            ren.SetWorldPoint(*p, 1.0)
            ren.WorldToDisplay()
            out.append(ren.GetDisplayPoint()[:2])
        return np.array(out)

    def _nearest(self, x: float, y: float) -> tuple[int, float] | None:
        """The joint drawn nearest display pixel (x, y) (of several under it, the one in
        front) and its distance, pixels, within :data:`PICK_RADIUS_PX`; None if none."""
        if self.positions is None:
            return None
        dist = np.linalg.norm(self._to_display(self.positions) - [x, y], axis=1)
        j = int(np.argmin(dist))
        under = np.flatnonzero(dist <= DRAWN_RADIUS_PX)
        if len(under) > 1:  # seen edge-on (the side view's elbows and knees): the one in front
            eye = np.asarray(self._plotter.camera.position, float)
            j = int(under[np.argmin(np.linalg.norm(self.positions[under] - eye, axis=1))])
        return None if dist[j] > PICK_RADIUS_PX else (j, float(dist[j]))

    def joint_at(self, x: float, y: float) -> int | None:
        """The joint a press at display pixel (x, y) grabs: the one drawn nearest, within
        :data:`PICK_RADIUS_PX`, or the joint it stands in for (:attr:`stand_ins`)."""
        near = self._nearest(x, y)
        if near is None:
            return None
        grabbed = self.stand_ins.get(JOINT_NAMES[near[0]])
        return near[0] if grabbed is None else JOINT_NAMES.index(grabbed)

    def press(self, x: float, y: float) -> bool:
        """Grab the joint under display pixel (x, y); True on a hit."""
        j = self.joint_at(x, y)
        if j is None or self.positions is None:
            return False
        self._grab_joint(j, x, y)
        return True

    def press_shifted(self, x: float, y: float) -> bool:
        """Grab :attr:`shift_grabs` when display pixel (x, y) lies within
        :data:`SHIFT_PICK_RADIUS_PX` of it; True on a hit."""
        if self.shift_grabs is None or self.positions is None:
            return False
        j = JOINT_NAMES.index(self.shift_grabs)
        if float(np.linalg.norm(self._to_display(self.positions[[j]])[0] - [x, y])) > SHIFT_PICK_RADIUS_PX:
            return False
        self._grab_joint(j, x, y)
        return True

    def _grab_joint(self, j: int, x: float, y: float) -> None:
        """Hold joint ``j`` from a press at display pixel (x, y)."""
        assert self.positions is not None
        self.joint, self._origin = j, self.positions[j].copy()
        base = None if self.drag_origin is None else self.drag_origin(JOINT_NAMES[j])
        self._start(x, y, self._origin if base is None else np.asarray(base, float))

    def _start(self, x: float, y: float, base: np.ndarray) -> None:
        """Remember what the drag moves and where the cursor met the drag plane at the press,
        so the grabbed thing moves with the cursor from where it is (no jump by the few
        pixels between the press and the joint's centre)."""
        self._base = base.copy()
        hit = self._hit(x, y)
        self._grab = self._origin.copy() if hit is None else hit[0]

    def _hit(self, x: float, y: float) -> tuple[np.ndarray, np.ndarray, np.ndarray] | None:
        """The point (3,) where the mouse ray at display pixel (x, y) meets the drag plane
        (through :attr:`_origin`, normal :meth:`drag_normal`), with the ray's direction and
        the plane's normal; None when they are parallel."""
        start, direction = self.ray(x, y)
        normal = self.drag_normal()
        denom = float(direction @ normal)
        if abs(denom) < 1e-12:
            return None
        return start + float((self._origin - start) @ normal) / denom * direction, direction, normal

    def press_target(self, x: float, y: float) -> bool:
        """Grab the tracker target whose sphere covers display pixel (x, y); True on a hit."""
        hit = None if self._sensors is None else self._sensors.pick(self._to_display, x, y)
        if hit is None:
            return False
        self.target, self._origin = hit
        self._start(x, y, self._origin)
        self._sensors.begin_drag(self.target)
        return True

    def press_plain(self, x: float, y: float) -> bool:
        """A press without Ctrl at display pixel (x, y): a target's sphere, else (with
        :attr:`plain_press_grabs_joints`) a joint; True on a hit."""
        return self.press_target(x, y) or (self.plain_press_grabs_joints and self.press(x, y))

    def release(self) -> None:
        """Let go of the held ring, joint or target."""
        if self.target is not None:
            self._sensors.end_drag()
        if self.ring is not None:
            self._rings.end()
        self.joint = self.target = self.ring = None

    def ray(self, x: float, y: float) -> tuple[np.ndarray, np.ndarray]:
        """The mouse ray at display pixel (x, y): a world point on it and its direction."""
        ren = self._plotter.renderer
        ends = []
        for z in (0.0, 1.0):
            ren.SetDisplayPoint(x, y, z)
            ren.DisplayToWorld()
            w = np.array(ren.GetWorldPoint())
            ends.append(w[:3] / w[3])
        return ends[0], ends[1] - ends[0]

    def drag_normal(self) -> np.ndarray:
        """Normal (3,) of the plane the held joint or target moves on: the view direction,
        made level for an :attr:`upright` one unless the camera looks steeply down (from
        above, a level plane is all the mouse can reach)."""
        cam = self._plotter.camera
        normal = np.asarray(cam.focal_point, float) - np.asarray(cam.position, float)
        name = self._held()
        if name in self.upright and abs(normal[2]) < UPRIGHT_STEEPEST * np.linalg.norm(normal):
            normal[2] = 0.0
        unit = normal / max(float(np.linalg.norm(normal)), 1e-12)
        axis = int(np.argmax(np.abs(unit)))
        if abs(unit[axis]) >= np.cos(np.radians(AXIS_SNAP_DEG)):
            return np.eye(3)[axis] * np.sign(unit[axis])
        return normal

    def _held(self) -> str | None:
        """The name of the target or joint held (None: neither)."""
        return self.target if self.target is not None else None if self.joint is None else JOINT_NAMES[self.joint]

    def move(self, x: float, y: float) -> None:
        """Drag the grabbed joint or target to display pixel (x, y)."""
        if self.joint is None and self.target is None:
            return
        hit = self._hit(x, y)
        if hit is None:
            return
        point, direction, normal = hit
        to = self._placed(self._base + (point - self._grab), self._base, direction, normal)
        if self.target is not None:
            if not self._sensors.drag(self.target, to):
                self.target = None  # the target went away: the rest of the drag moves nothing
                return
            self._plotter.render()  # the sphere follows the mouse at once, as a widget's did
        else:
            self._on_drag(JOINT_NAMES[self.joint], to)

    def _placed(self, point: np.ndarray, pressed: np.ndarray, direction: np.ndarray, normal: np.ndarray) -> np.ndarray:
        """Where the held thing goes for ``point (3,)`` on its drag plane: :attr:`place`'s
        answer (on the line through ``point`` along the mouse ray's ``direction``, which
        keeps it under the cursor), or ``point``; ``pressed``: where the drag began."""
        name = self._held()
        if self.place is None or name is None:
            return point
        return np.asarray(self.place(name, point, pressed, point, direction, normal), float)
