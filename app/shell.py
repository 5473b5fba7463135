"""What the app's helpers may use of the window they serve, as typed protocols.

The studio's helpers (saving, drawing, failure countdowns, ghost status, measuring,
range re-solves, the authoring entries, the redraw from session events) take
the main window as a :class:`StudioShell`: the session, the widgets and the few window
services they call, and nothing else. The menu parts shared with the pose window take a
:class:`ViewWindow`. Both are ``runtime_checkable``; a test checks that
:class:`app.main_window.MainWindow` satisfies them, so a helper that starts using
something the window lacks, or a window that drops something a helper uses, fails there.

The helpers' own objects the window holds (its scene files, ghost status, draw
scheduler, motion paths) appear as the small protocols below, not as their classes:
those modules import this one (the motion paths through the shared menu parts), and
naming their classes here would make an import loop.
"""

from __future__ import annotations

from collections import deque
from collections.abc import Callable
from typing import TYPE_CHECKING, Any, Protocol, runtime_checkable

import numpy as np

if TYPE_CHECKING:
    from PyQt6.QtCore import QSettings, Qt, pyqtBoundSignal
    from PyQt6.QtWidgets import QDialog, QDockWidget, QLabel, QMainWindow, QMenuBar, QStatusBar

    from app.busy import BusyNotice
    from app.job_runner import JobRunner
    from app.undo import SceneUndo
    from engine.motion.clip import Motion
    from engine.studio.session import Session
    from widgets.constraint_panel import ConstraintPanel
    from widgets.latent_inspector import LatentInspector
    from widgets.method_errors import MethodErrorPlot
    from widgets.optimizer_panel import OptimizerPanel
    from widgets.plots import LossPlots
    from widgets.sensor_panel import SensorPanel
    from widgets.timeline import Timeline
    from widgets.viewport import Viewport


class SceneFiles(Protocol):
    """The window's scene files (:class:`app.file_actions.FileActions`), as saving uses them."""

    def save_scene(self, path: str | None = None) -> bool: ...

    def suggested_name(self, ext: str, what: str | None = None) -> str: ...


class GhostProblems(Protocol):
    """The window's ghost status (:class:`app.ghost_status.GhostStatus`), as drawing and
    the redraw from session events use it."""

    def is_ghost_problem(self, message: str) -> bool: ...

    def on_snapshot(self, snap: Any) -> None: ...

    def apply(self) -> None: ...

    def sensors_changed(self, event: Any = None) -> None: ...


class PathSource(Protocol):
    """The window's motion paths (:class:`app.motion_path_view.MotionPathView`), as the
    redraw from session events uses them: where the paths of a new clip come from."""

    def set_source(self, source: Callable[[], Any] | None) -> None: ...


class TimedPanel(Protocol):
    """One panel of the draw scheduler: ``costs``, its update times in ms."""

    costs: deque


class DrawRecord(Protocol):
    """The window's draw scheduler (:class:`app.drawing.DrawScheduler`), as ``gui
    --measure`` reads it: view draws, their costs (ms) and each panel's."""

    draws: int
    view_costs: deque
    panels: list[TimedPanel]  # the latent views add theirs (app/latent_views.py)

    def costs(self) -> dict[str, dict[str, float]]: ...


@runtime_checkable
class ViewWindow(Protocol):
    """A window with a 3D view (the studio, the pose window), as the shared menu parts
    use it: its viewport, the point the camera presets look at, its menu bar."""

    viewport: Viewport
    #: What the mouse does in its 3D view, ``(gesture, what)`` rows for Help (F1).
    mouse_help: tuple[tuple[str, str], ...]

    def hips(self) -> np.ndarray | None: ...

    def menuBar(self) -> QMenuBar: ...


@runtime_checkable
class StudioShell(Protocol):
    """The studio's main window as its helpers use it (:class:`app.main_window.MainWindow`).

    Attributes
    ----------
    session : Session
        The Qt-free model every edit goes through.
    opened_motion : Motion or None
        The clip as opened, before any range re-solve replaced ``session.motion``.
    snapshotDrawn : bound signal (int)
        Emitted with the frame of each drawn snapshot.
    status_engine, status_gui, status_warnings : QLabel
        The status bar's solver, view and warning figures.
    settings : QSettings
        The window's persistent settings.
    tabifiedDockWidgetActivated : bound signal (QDockWidget)
        A tabbed dock was brought to the front.
    timeline : Timeline
        The play bar, with the frame range selected on it.
    range_jobs : JobRunner or None
        The runner of range re-solves (:mod:`app.range_actions`), made on first use.
    range_dialog : QDialog or None
        The last Re-solve range dialog shown (tests answer it).
    pose_windows : list of QMainWindow
        The pose windows opened from File ▸ New pose (:mod:`app.authoring_actions`).
    autosave : StudioAutosave or None
        The autosave of the window and its pose windows (:mod:`app.autosave`), when on.
    motion_paths : PathSource
        The motion paths in the 3D view (:mod:`app.motion_path_view`).
    optimizer_defaults : dict
        Each optimizer setting's default, by name: what the optimizer panel shows for a
        setting the session has not set.
    trim_entry : TrimEntry
        Edit ▸ Trim clip to selection (:mod:`app.clip_trim`), closed with the window.
    """

    session: Session
    opened_motion: Motion | None
    viewport: Viewport
    plots: LossPlots
    latent: LatentInspector
    method_errors: MethodErrorPlot
    optimizer_panel: OptimizerPanel
    optimizer_defaults: dict[str, Any]
    constraint_panel: ConstraintPanel
    motion_paths: PathSource
    sensor_panel: SensorPanel
    undo: SceneUndo
    busy: BusyNotice
    files: SceneFiles
    ghost_status: GhostProblems
    drawing: DrawRecord
    snapshotDrawn: pyqtBoundSignal
    status_engine: QLabel
    status_gui: QLabel
    status_warnings: QLabel
    timeline: Timeline
    settings: QSettings
    tabifiedDockWidgetActivated: pyqtBoundSignal
    range_jobs: JobRunner | None
    range_dialog: QDialog | None
    pose_windows: list[QMainWindow]
    autosave: Any
    trim_entry: Any

    def show_error(self, title: str, message: str) -> None: ...

    def findChild(self, kind: type, name: str = "") -> Any: ...

    def addDockWidget(self, area: Qt.DockWidgetArea, dock: QDockWidget) -> None: ...

    def tabifyDockWidget(self, first: QDockWidget, second: QDockWidget) -> None: ...

    def statusBar(self) -> QStatusBar: ...

    def width(self) -> int: ...

    def height(self) -> int: ...
