"""The 3D viewport widget: holds a pyvistaqt interactor and the drawable adapters."""

from __future__ import annotations

import time
from collections.abc import Callable
from typing import Any

import numpy as np
import vtk
from PyQt6.QtCore import QEvent, QObject, Qt, pyqtSignal
from PyQt6.QtGui import QImage
from PyQt6.QtWidgets import QVBoxLayout, QWidget

from widgets import style
from widgets.viewport.body import BodyActor
from widgets.viewport.camera import CAMERA_PRESETS, place_camera
from widgets.viewport.floor import FloorGrid
from widgets.viewport.ghosts import GhostLayer
from widgets.viewport.gizmos import ConstraintGizmos
from widgets.viewport.native import make_plotter
from widgets.viewport.paths import MotionPathLayer
from widgets.viewport.picking import JointDragger
from widgets.viewport.rings import RotationRings
from widgets.viewport.sensors import SensorMarkers
from widgets.viewport.skeleton import SkeletonActor
from widgets.viewport.wheel_zoom import WheelZoom

HOME_FOCUS_HEIGHT = 0.9
#: The caption's font size, pixels, for every caption and window size: VTK's corner text
#: (pyvista's ``add_text`` at a corner) scales with the window and shrinks a longer line
#: to fit, which would draw "no ground truth (tracker input)" smaller than "ground truth
#: (green)". A plain text actor keeps its size (the ghost legend below it is 15 too).
CAPTION_FONT_PX = 15
FOLLOW_TIME_S = 0.25  # camera-follow time constant, seconds
#: How the reconstruction is drawn: a stick figure, or a shaded capsule mannequin.
DISPLAY_MODES = ("stick", "body")
_BUTTON_HELD = (QEvent.Type.MouseButtonPress, QEvent.Type.MouseMove)


def keep_key_lights(renderer: Any) -> None:
    """Switch off all of pyvista's light kit but the headlight and the key light.

    Every lit pixel evaluates every light; on software GL the fill and two back lights
    cost ~1.2 ms of a ~18 ms draw here and barely change the picture (the key light
    gives the shape, the headlight the rest)."""
    lights = [renderer.GetLights().GetItemAsObject(i) for i in range(renderer.GetLights().GetNumberOfItems())]
    others = [light for light in lights if not light.LightTypeIsHeadlight()]
    key = max(others, key=lambda light: light.GetIntensity(), default=None)
    for light in others:
        if light is not key:
            light.SwitchOff()


def caption_actor(renderer: Any) -> vtk.vtkTextActor:
    """The caption line at the view's top left, :data:`CAPTION_FONT_PX` high whatever it
    says and whatever the window's size."""
    actor = vtk.vtkTextActor()
    prop = actor.GetTextProperty()
    prop.SetFontSize(CAPTION_FONT_PX)
    prop.SetColor(*style.hex_to_unit_rgb("#d0d4dc"))
    prop.SetVerticalJustificationToTop()
    where = actor.GetPositionCoordinate()
    where.SetCoordinateSystemToNormalizedViewport()
    where.SetValue(0.004, 0.992)
    actor.PickableOff()
    renderer.AddViewProp(actor)
    return actor


class Viewport(QWidget):
    """Draws snapshots: reconstruction, ground truth, ghosts, sensors, gizmos, floor.

    Signals
    -------
    targetDragged(str, object)
        A sensor target was dragged to a new world position (ndarray (3,), metres).
    jointDragged(str, object)
        Ctrl + drag on a joint of the reconstruction: joint name and world position.
    gizmoEdited(str, object)
        A constraint gizmo was dragged; ``dict`` of field name -> new value.
    filesDropped(list)
        Local file paths dropped on the 3D view.
    ringTurned(int, float, bool)
        A rotation ring (:attr:`rings`, shown by its owner) is dragged: its axis (0, 1,
        2: world X, Y, Z), the radians swept since the press, and whether this is the press.
    jointSelected(str)
        A joint (or a target, by its joint) was grabbed or clicked: its name.
    mouseReleased()
        A mouse button pressed on the view is up (before the view handles the release).
    """

    targetDragged = pyqtSignal(str, object)
    jointDragged = pyqtSignal(str, object)
    gizmoEdited = pyqtSignal(str, object)
    filesDropped = pyqtSignal(list)
    ringTurned = pyqtSignal(int, float, bool)
    jointSelected = pyqtSignal(str)
    mouseReleased = pyqtSignal()

    def __init__(self, parent: QWidget | None = None) -> None:
        super().__init__(parent)
        layout = QVBoxLayout(self)
        layout.setContentsMargins(0, 0, 0, 0)
        self.plotter = make_plotter(self)
        # pyvistaqt accepts any dropped file and tries to read it as a mesh; take the
        # drops here instead so a .bvh dropped on the view opens like one on the window;
        # the filter also keeps keys from VTK and pyvista (see eventFilter)
        self.plotter.installEventFilter(self)
        self.plotter.iren.clear_key_event_callbacks()
        layout.addWidget(self.plotter)
        p = self.plotter
        p.set_background(style.BACKGROUND_TOP)
        keep_key_lights(p.renderer)
        self.floor = FloorGrid(p)
        self.ground_truth = SkeletonActor(p, style.GROUND_TRUTH, bone_width=4, joint_size=8, name="ground-truth")
        self.reconstruction = SkeletonActor(p, style.RECONSTRUCTION, name="reconstruction")
        self.body = BodyActor(p, style.RECONSTRUCTION, name="body")
        self.body.set_visible(False)
        self.display = "stick"
        self.decoded = SkeletonActor(p, "#ffffff", bone_width=4, joint_size=7, name="decoded")
        self.decoded.set_visible(False)
        self.ghosts = GhostLayer(p)
        self.sensors = SensorMarkers(p, lambda j, pos: self.targetDragged.emit(j, pos))
        self.rings = RotationRings(p)
        self.joints = JointDragger(
            p,
            lambda j, pos: self.jointDragged.emit(j, pos),
            self.sensors,
            self.rings,
            lambda axis, angle, first: self.ringTurned.emit(axis, angle, first),
            self.jointSelected.emit,
        )
        self.paths = MotionPathLayer(p)
        self.gizmos = ConstraintGizmos(p, lambda n, changes: self.gizmoEdited.emit(n, changes))
        self.wheel_zoom = WheelZoom(p)
        self._label = caption_actor(p.renderer)
        self._notice = p.add_text("", position="lower_edge", font_size=12, color="#ffe14d")
        self.notice = ""
        self._caption = ""
        self.follow = True
        self._show_ground_truth = True
        self._last_snap: Any = None  # the snapshot drawn last, drawn again when a view option changes
        #: The keyboard modifiers of the mouse press or move being handled, while a button
        #: is held (None otherwise): a drag signal emitted from that event can ask which
        #: keys were held then (a live query answers for the time the event is handled,
        #: which, with the event queue behind on a busy machine, can be after a key's release).
        self.drag_modifiers: Qt.KeyboardModifier | None = None
        #: Whether a mouse button pressed on the view is still held: a selection made by
        #: the press belongs to the drag that may follow, not to a click.
        self.mouse_held = False
        self.camera_preset = "home"
        #: Joints whose tracker has an orientation (6-DoF); None draws axes on every target.
        self.oriented: frozenset[str] | None = None
        self._focus = np.array([0.0, 0.0, HOME_FOCUS_HEIGHT])
        #: Seconds clock of the follow camera's glide (tests replace it).
        self.clock: Callable[[], float] = time.monotonic
        self._followed_at = self.clock()
        self.reset_camera()

    # -- camera ---------------------------------------------------------------------
    @property
    def show_ghosts(self) -> bool:
        return self.ghosts.visible

    @show_ghosts.setter
    def show_ghosts(self, on: bool) -> None:
        self.ghosts.visible = bool(on)
        self._redraw()

    @property
    def show_ground_truth(self) -> bool:
        return self._show_ground_truth

    @show_ground_truth.setter
    def show_ground_truth(self, on: bool) -> None:
        self._show_ground_truth = bool(on)
        self._redraw()

    def _redraw(self) -> None:
        """Draw the last snapshot again (a view option changed): a paused studio draws
        nothing else until the next edit or frame."""
        if self._last_snap is not None:
            self.show_snapshot(self._last_snap)
        else:
            self.plotter.render()

    def reset_camera(self, focus: np.ndarray | None = None) -> None:
        """Look at ``focus`` (default: the current hips) from the front-left."""
        self.set_camera("home", focus)

    def set_camera(self, preset: str, focus: np.ndarray | None = None) -> None:
        """Place the camera at a preset (``home``, ``front``, ``side``, ``top``) around
        ``focus`` (default: the followed hips); see :mod:`widgets.viewport.camera`.

        Renders at once: a paused studio or a pose window draws nothing else until the
        next edit, so the new view would otherwise wait for an unrelated repaint."""
        if preset not in CAMERA_PRESETS:
            raise ValueError(f"unknown camera preset {preset!r}; known: {', '.join(CAMERA_PRESETS)}")
        if focus is not None:
            self._focus = np.array([focus[0], focus[1], HOME_FOCUS_HEIGHT])
        self.camera_preset = preset
        place_camera(self.plotter.camera, preset, self._focus)
        self.plotter.reset_camera_clipping_range()
        self.plotter.render()

    def set_display(self, mode: str) -> None:
        """Draw the reconstruction as a ``stick`` figure or a shaded ``body``."""
        if mode not in DISPLAY_MODES:
            raise ValueError(f"unknown display mode {mode!r}; known: {', '.join(DISPLAY_MODES)}")
        self.display = mode
        if mode == "stick":
            self.body.set_visible(False)
        else:
            self.reconstruction.set_visible(False)
        self._redraw()

    def frame(self, point: np.ndarray) -> None:
        """Centre the view on ``point (3,)`` metres, keeping the camera's angle and distance."""
        cam = self.plotter.camera
        delta = np.asarray(point, float) - np.asarray(cam.GetFocalPoint())
        self._focus = self._focus + delta
        cam.SetFocalPoint(*(np.asarray(cam.GetFocalPoint()) + delta))
        cam.SetPosition(*(np.asarray(cam.GetPosition()) + delta))
        self.plotter.reset_camera_clipping_range()
        self.plotter.render()

    def _follow(self, root: np.ndarray, glide: bool = True) -> None:
        """Slide camera and focus horizontally with the hips, keeping the user's angle;
        ``glide`` False goes all the way at once (a paused frame: no later redraw would
        finish a glide, and the view would stay part way, off the character)."""
        now = self.clock()
        dt, self._followed_at = now - self._followed_at, now
        goal = np.array([root[0], root[1], self._focus[2]])
        # time-based smoothing: the same glide at 60 or 5 redraws per second
        share = 1.0 - np.exp(-dt / FOLLOW_TIME_S) if glide else 1.0
        delta = share * (goal - self._focus)
        if np.linalg.norm(delta) < 1e-5:
            return
        cam = self.plotter.camera
        self._focus = self._focus + delta
        # VTK's setters: pyvista's ``position`` setter resets the clipping range itself,
        # and that bounds query over every actor would then run twice per frame
        cam.SetFocalPoint(*(np.asarray(cam.GetFocalPoint()) + delta))
        cam.SetPosition(*(np.asarray(cam.GetPosition()) + delta))
        self.plotter.reset_camera_clipping_range()

    # -- drawing --------------------------------------------------------------------
    def show_snapshot(self, snap: Any) -> None:
        """Draw an engine snapshot (typed against ``engine.studio.snapshot.Snapshot``)."""
        self._last_snap = snap
        (self.body if self.display == "body" else self.reconstruction).update(snap.positions)
        self.joints.positions = np.asarray(snap.positions)
        self.ground_truth.update(snap.ground_truth if self.show_ground_truth else None)
        self.ghosts.update(snap.ghosts)
        self.decoded.update(snap.decoded)
        # a 3-DoF tracker has no orientation: axes on it would show a made-up one
        axes = None if self.oriented is None else tuple(j in self.oriented for j in snap.target_joints)
        self.sensors.update(
            snap.target_joints, snap.target_positions, snap.target_rotations, snap.target_connected, axes
        )
        self.gizmos.update(snap.gizmos)
        if self.paths.shown:
            self.paths.at_frame(snap.frame)
        # ghosts are listed below this line by the ghost layer, each in its own colour
        has_gt = bool(np.all(np.isfinite(snap.ground_truth)))
        gt = (
            ("   ground truth (green)" if has_gt else "   no ground truth (tracker input)")
            if self.show_ground_truth
            else ""
        )
        caption = f"{snap.method or 'method'} (orange){gt}"
        if caption != self._caption:  # a text change re-renders its glyphs: only on change
            self._caption = caption
            self._label.SetInput(caption)
        if self.follow and np.all(np.isfinite(snap.positions[0])):
            self._follow(snap.positions[0], glide=bool(snap.playing))
        self.plotter.render()

    def clear_pose(self, caption: str = "") -> None:
        """Take down every pose the last snapshot drew (reconstruction, ground truth,
        ghosts, decoded latent, targets, gizmos) and say ``caption`` instead: another clip
        or sensor source opened, and nothing of it is solved yet. A live stream that has
        sent no frame yet must not show the previous source's character as if it were its own."""
        self._last_snap = None
        self.reconstruction.update(None)
        self.body.update(None)
        self.ground_truth.update(None)
        self.decoded.update(None)
        self.ghosts.update({})
        self.sensors.update((), np.zeros((0, 3)), np.zeros((0, 4)), np.zeros(0, bool))
        self.gizmos.update(())
        self.joints.positions = None  # nothing to pick
        if caption != self._caption:
            self._caption = caption
            self._label.SetInput(caption)
        self.plotter.render()

    def show_clip_frame(self, positions: np.ndarray) -> None:
        """Draw a newly opened clip's frame (22, 3) m as the ground truth at once, before
        the engine has solved anything (loading a model and the first solve take seconds)."""
        if self.show_ground_truth:
            self.ground_truth.update(np.asarray(positions, float))
        self.plotter.render()

    def set_notice(self, text: str) -> None:
        """A line of text at the bottom of the view ("" removes it), e.g. while a model loads."""
        if text != self.notice:
            self.notice = text
            self._notice.SetText(4, text)  # vtkCornerAnnotation.LowerEdge
            self.plotter.render()

    def grab_image(self) -> QImage:
        """The render window's current image (QWidget.grab() may miss OpenGL content)."""
        img = np.ascontiguousarray(self.plotter.screenshot(return_img=True))
        h, w = img.shape[:2]
        return QImage(img.data, w, h, 3 * w, QImage.Format.Format_RGB888).copy()

    def eventFilter(self, obj: QObject | None, event: QEvent | None) -> bool:
        """Take file drags and drops from the VTK widget (see ``__init__``), and keep
        every key from it: VTK's interactor style and pyvista bind plain letters to
        stereo (3), wireframe (w), a camera reset (r), picking modes (b, p, C) and
        closing the render window (q, e), none of which the menus show, and the
        window's shortcuts have already taken the keys they bind. The wheel zooms
        toward the mouse (:mod:`widgets.viewport.wheel_zoom`), not VTK's centre."""
        if event is not None and event.type() in (QEvent.Type.KeyPress, QEvent.Type.KeyRelease):
            event.ignore()
            return True
        if event is not None and event.type() in _BUTTON_HELD:
            # the keys held with this press or move, as the X server saw them then
            self.drag_modifiers = event.modifiers()  # type: ignore[attr-defined]
        elif event is not None and event.type() == QEvent.Type.MouseButtonRelease:
            self.drag_modifiers = None
            self.mouse_held = False
            self.mouseReleased.emit()
        if event is not None and event.type() == QEvent.Type.MouseButtonPress:
            self.mouse_held = True
        if event is not None and event.type() == QEvent.Type.Wheel:
            self.wheel_zoom.wheel(event)
            event.accept()
            return True
        if event is not None and event.type() in (QEvent.Type.DragEnter, QEvent.Type.DragMove, QEvent.Type.Drop):
            paths = [u.toLocalFile() for u in event.mimeData().urls() if u.isLocalFile()]
            if paths:
                event.acceptProposedAction()
                if event.type() == QEvent.Type.Drop:
                    self.filesDropped.emit(paths)
            else:
                event.ignore()
            return True
        return super().eventFilter(obj, event)

    def close(self) -> bool:
        """Release widgets and the VTK interactor (no interactor may outlive the view)."""
        self.plotter.removeEventFilter(self)
        self.sensors.clear()
        self.rings.clear()
        self.gizmos.clear()
        self.paths.clear()
        self.ghosts.close()
        self.plotter.close()
        return super().close()
