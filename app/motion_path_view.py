"""View ▸ Motion paths (P) and View ▸ Feet paths (Shift+P), shared by the studio and the
pose window: which paths a window draws and when.

The window hands over its paths (:class:`engine.authoring.motion_paths.MotionPaths`,
or a function that computes them, asked only while something is to be drawn) and its
selected joint; this object draws the selected joint's path and, when asked, both feet's
in the view's :class:`widgets.viewport.paths.MotionPathLayer`. Both toggles are
remembered in the window's settings (the studio's, which the pose window shares).
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
from PyQt6.QtCore import QObject, QSettings, QTimer
from PyQt6.QtGui import QAction
from PyQt6.QtWidgets import QMenu

from app.menu_parts import toggle
from engine import skeleton as sk
from engine.authoring.motion_paths import MotionPaths, path_joints
from widgets.viewport.paths import MotionPathLayer

#: Settings keys of the two toggles.
SHOW_KEY = "view/motion_paths"
FEET_KEY = "view/motion_paths_feet"
#: The selected joint's path, and the feet's (left, right).
SELECTED_COLOUR = "#ffd24d"
FEET_COLOURS = {"lankle": "#4dd0ff", "rankle": "#8f7dff"}


class MotionPathView:
    """The motion paths of one window (see the module doc).

    Parameters
    ----------
    layer : MotionPathLayer
        The view's path drawable.
    settings : QSettings
        Where the toggles are remembered.
    render : callable
        Asks the view to draw again.
    frame : callable or None
        The frame on screen, where newly drawn paths put their current-frame dot (the
        studio's; the pose window marks its pose instead, :meth:`mark_pose`).
    """

    def __init__(
        self,
        layer: MotionPathLayer,
        settings: QSettings,
        render: Callable[[], None],
        frame: Callable[[], int] | None = None,
    ) -> None:
        self.layer = layer
        self.settings = settings
        self.render = render
        self.frame = frame
        self.on = bool(settings.value(SHOW_KEY, True, type=bool))
        self.feet = bool(settings.value(FEET_KEY, False, type=bool))
        self.selected: str | None = None
        self.paths: MotionPaths | None = None
        self._source: Callable[[], MotionPaths | None] | None = None
        self._pose: np.ndarray | None = None  # the pose last marked (mark_pose)
        self._pending = False  # a source_changed waits for the event loop
        self._next: Callable[[], MotionPaths | None] | None = None
        self.actions: dict[str, QAction] = {}

    def add_menu_entries(self, window: QObject, view: QMenu) -> dict[str, QAction]:
        """The two toggles on the View menu ``view``; the actions by name."""
        view.addSeparator()
        self.actions = {
            "motion_paths": toggle(window, view, "&Motion paths", self.on, self.set_on, "P"),
            "feet_paths": toggle(window, view, "Motion paths of the &feet", self.feet, self.set_feet, "Shift+P"),
        }
        return self.actions

    @property
    def joints(self) -> tuple[str, ...]:
        """The joints whose paths are drawn now."""
        return path_joints(self.selected, self.feet) if self.on else ()

    def set_on(self, on: bool) -> None:
        self.on = bool(on)
        self.settings.setValue(SHOW_KEY, self.on)
        self.refresh()

    def set_feet(self, on: bool) -> None:
        self.feet = bool(on)
        self.settings.setValue(FEET_KEY, self.feet)
        self.refresh()

    def select(self, joint: str | None) -> None:
        """Draw the path of ``joint`` (None: of no joint but the feet)."""
        if joint != self.selected:
            self.selected = joint
            self.refresh()

    def set_source(self, source: Callable[[], MotionPaths | None] | None) -> None:
        """Take the paths from ``source()`` from now on (asked now, when anything is drawn,
        else when something is to be drawn)."""
        self._source = source
        self.paths = None
        self.refresh()

    def source_changed(self, source: Callable[[], MotionPaths | None]) -> None:
        """:meth:`set_source` once the events of the edit going on are all out (an edit
        that changes the keys and the bake asks once)."""
        self._next = source
        if not self._pending:
            self._pending = True
            QTimer.singleShot(0, self._take_next)

    def _take_next(self) -> None:
        self._pending = False
        self.set_source(self._next)

    def refresh(self) -> None:
        """Draw the paths of :attr:`joints` (computing them first when they are due)."""
        joints = self.joints
        if joints and self.paths is None and self._source is not None:
            self.paths = self._source()
            self._source = None
        p = self.paths
        if not joints or p is None:
            self.layer.hide()
        else:
            colours = {j: FEET_COLOURS.get(j, SELECTED_COLOUR) for j in joints}
            colours.update({self.selected: SELECTED_COLOUR} if self.selected in colours else {})
            self.layer.show(p.first, {j: p.line(j) for j in joints}, colours, p.marks)
            if self._pose is not None:  # the joints drawn may have changed
                self.mark_pose(self._pose)
            elif self.frame is not None:
                self.layer.at_frame(self.frame())
        self.render()

    def at_frame(self, frame: int) -> None:
        """The current-frame dots on ``frame`` of the paths (no render)."""
        if self.layer.shown:
            self.layer.at_frame(frame)

    def mark_pose(self, positions: np.ndarray) -> None:
        """The current-frame dots on the drawn joints of ``positions (22, 3)`` metres: the
        pose on screen, which a drag changes before any key does (no render)."""
        self._pose = np.array(positions, float)
        if self.layer.shown:
            self.layer.mark_current(np.asarray(positions, float)[[sk.JOINT_INDEX[j] for j in self.joints]])
