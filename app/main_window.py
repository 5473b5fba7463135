"""The studio's main window: wires the session, the engine thread and the widgets.

Data flow: widgets emit requests -> the window calls :class:`engine.studio.session.Session`
methods -> the session forwards commands to its engine thread. The engine publishes
snapshots; a display-rate QTimer draws only the newest one, so the GUI never waits on
the engine (:class:`app.drawing.DrawScheduler` decides what each tick draws). Typed
session events update only the widget that shows what changed.
"""

from __future__ import annotations

import gc
import sys
from typing import Any

import numpy as np
from PyQt6.QtCore import QSettings, Qt, QTimer, pyqtSignal
from PyQt6.QtWidgets import (
    QApplication,
    QDockWidget,
    QFrame,
    QLabel,
    QMainWindow,
    QMessageBox,
    QScrollArea,
    QTabWidget,
    QVBoxLayout,
    QWidget,
)

from app import authoring_actions, clip_saving
from app.busy import BusyNotice
from app.camera_keys import CameraKeys
from app.constraint_placement import moved_params, placed_params
from app.constraint_ranges import link_ranges
from app.drawing import DrawScheduler
from app.failures import FailureCountdown
from app.file_actions import FileActions
from app.ghost_status import GhostStatus
from app.latent_views import LatentViews
from app.live_actions import LiveActions
from app.menus import build_menus
from app.motion_path_view import MotionPathView
from app.schema import constraint_schema, optimizer_fields
from app.status_bar import StatusBar
from app.studio_redraw import StudioRedraw
from app.undo import SceneUndo
from engine.errors import UserError
from engine.motion.source_file import is_source_file
from engine.studio.session import Session
from engine.studio.session_sensors import SensorSet
from widgets.constraint_panel import ConstraintPanel
from widgets.help_dialog import MOUSE
from widgets.latent_inspector import LatentInspector
from widgets.method_errors import MethodErrorPlot
from widgets.optimizer_panel import OptimizerPanel
from widgets.plots import LossPlots
from widgets.sensor_panel import SensorPanel
from widgets.timeline import Timeline
from widgets.viewport import Viewport


def method_names(current: str) -> list[str]:
    """Registered methods (plus ``current``, so an unknown one is shown, not hidden)."""
    names = Session.available_methods()
    return names + ([current] if current not in names else [])


class MainWindow(QMainWindow):
    """The studio. ``snapshotDrawn(int)`` fires after each drawn snapshot (its frame).

    ``engine="process"`` (the default) runs the solver in a child process
    (:mod:`engine.studio.process`), ``"thread"`` in a thread of this one (tests use it to
    reach the engine's internals). ``started``: an engine process already started
    (``gui`` starts it before importing Qt: :func:`app.cli.run`), used instead of a new one.
    """

    mouse_help = MOUSE

    snapshotDrawn = pyqtSignal(int)

    def __init__(
        self, method: str = "ik", settings: QSettings | None = None, engine: str = "process", started: Any = None
    ) -> None:
        super().__init__()
        self.setStatusBar(StatusBar())  # before any message: the readouts give way to every one
        self.setWindowTitle("DragPoser Studio")
        self.setAcceptDrops(True)
        self.settings = settings or QSettings("dragposer-studio", "studio")
        self.session = Session(method=method)
        self.opened_motion = None  # the clip as opened, which a range re-solve replaces
        self.range_jobs = None  # a JobRunner made on the first re-solve (app.range_actions)
        self.range_dialog = None  # the last Re-solve range dialog (tests answer it)
        self.pose_windows: list[QMainWindow] = []  # File ▸ New pose (app.authoring_actions)
        self.autosave: Any = None  # an app.autosave.StudioAutosave when `gui` autosaves
        self._build_widgets()
        self.busy = BusyNotice(self.viewport, self.statusBar())
        self.busy.begin(method, -1, "Starting")
        # after the widgets: the thread's first imports would compete with theirs
        self.session.start_engine(process=engine == "process", started=started)
        self.files = FileActions(self, self.session, self.settings, self.viewport, self.show_error)
        self.live = LiveActions(self, self.session, self.timeline, self.plots, self.settings, self.show_error)
        self.undo = SceneUndo(self.session, self)
        self._preset_chosen = False  # a preset chosen in the panel: remembered once kept
        self.undo.kept.connect(self._remember_preset)
        self.files.confirm_discard = lambda doing: clip_saving.confirm_discard(self, doing)
        self.failures = FailureCountdown(self)
        self.snapshotDrawn.connect(self.failures.on_frame)
        self.ghost_status = GhostStatus(self)
        self.motion_paths = MotionPathView(
            self.viewport.paths, self.settings, self.viewport.plotter.render, lambda: self.session.frame
        )
        build_menus(self)
        # the follow camera beside the play controls, where a walking character's user looks
        self.follow_button = self.timeline.add_action(self.actions_by_name["follow"])
        self.camera_keys = CameraKeys(self.viewport, self)
        QApplication.instance().installEventFilter(self.camera_keys)
        self.redraw = StudioRedraw(self)
        self.redraw.refresh()
        self.drawing = DrawScheduler(self)
        self.latent_views = LatentViews(self)  # the latent map dock, drawn by the scheduler's panels
        self.timer = QTimer(self, interval=self.drawing.interval_ms)
        self.timer.timeout.connect(self.drawing.tick)
        self.timer.start()
        # Everything imported so far (torch, VTK, Qt: ~10^6 objects) never dies; freezing it
        # keeps the cyclic GC's full passes from pausing the GUI for 100+ ms at a time.
        gc.freeze()
        # The engine thread runs Python between its numpy/torch calls; every GIL-releasing
        # Qt or VTK call here then waits up to the switch interval to get the GIL back
        # (5 ms by default), which adds up to whole blocked frames. 0.5 ms keeps the GUI
        # thread's waits short at a small cost in engine throughput.
        sys.setswitchinterval(min(sys.getswitchinterval(), 0.0005))
        geometry = self.settings.value("geometry")
        if geometry is not None:
            self.restoreGeometry(geometry)
        else:
            self.resize(1600, 980)

    @property
    def engine(self) -> Any:
        """The session's engine (a thread, or a process: see ``engine`` in ``__init__``)."""
        return self.session.engine

    # -- layout -----------------------------------------------------------------------
    def _build_widgets(self) -> None:
        self.viewport = Viewport(self)
        self.timeline = Timeline(self)
        central = QWidget()
        col = QVBoxLayout(central)
        col.setContentsMargins(0, 0, 0, 0)
        col.setSpacing(0)
        col.addWidget(self.viewport, 1)
        col.addWidget(self.timeline)
        self.setCentralWidget(central)
        self.sensor_panel = SensorPanel(SensorSet.presets())
        self.constraint_panel = ConstraintPanel(
            constraint_schema(),
            empty_hint="No constraints yet: pick a kind above and press Add (it is placed near the "
            "character), or Ctrl-drag a joint in the 3D view to pin it where you drop it.",
        )
        fields = optimizer_fields()
        self.optimizer_defaults = {f.name: f.default for f in fields}
        self.optimizer_panel = OptimizerPanel(method_names(self.session.method), fields)
        tabs = QTabWidget()
        tabs.addTab(self.sensor_panel, "Sensors")
        tabs.addTab(self.constraint_panel, "Constraints")
        # the settings scroll: at their full height the dock, and the window, would be taller
        # than a laptop screen
        settings = QScrollArea(widgetResizable=True, frameShape=QFrame.Shape.NoFrame)
        settings.setWidget(self.optimizer_panel)
        tabs.addTab(settings, "Optimizer")
        self.latent = LatentInspector()
        self.plots = LossPlots()
        scene = self._dock("Scene", tabs, Qt.DockWidgetArea.RightDockWidgetArea)
        latent = self._dock("Latent", self.latent, Qt.DockWidgetArea.RightDockWidgetArea)
        plots = self._dock("Optimizer plots", self.plots, Qt.DockWidgetArea.BottomDockWidgetArea)
        self.method_errors = MethodErrorPlot()  # each method's error against the clip, per frame
        self.method_errors_dock = self._dock(
            "Method errors", self.method_errors, Qt.DockWidgetArea.BottomDockWidgetArea
        )
        self.tabifyDockWidget(plots, self.method_errors_dock)
        plots.raise_()
        # the right column runs the full height, so the latent dock has room for its
        # 24-row history strip; the plots sit under the 3D view only
        self.setCorner(Qt.Corner.BottomRightCorner, Qt.DockWidgetArea.RightDockWidgetArea)
        self.resizeDocks([scene, latent], [430, 430], Qt.Orientation.Horizontal)
        self.resizeDocks([scene, latent], [480, 420], Qt.Orientation.Vertical)
        self.resizeDocks([plots], [300], Qt.Orientation.Vertical)
        self.status_engine = QLabel()
        self.status_gui = QLabel()
        self.status_warnings = QLabel()
        # fixed widths that hold the longest texts (app/drawing.py sets short texts, details
        # in tooltips): a text change must not relayout the window every frame. The solver
        # and view readouts are the status bar's normal widgets, which it hides while a
        # message shows, so a message gets the bar's width (permanent ones would keep
        # half of it and cut the message off).
        for w, longest, permanent in (
            (self.status_engine, "solver 9999 frames/s   99999 ms/frame   999 it   99.99 ms/it   skipped 99999", False),
            (self.status_gui, "view 999 draws/s", False),
            (self.status_warnings, "warnings 9999", True),
        ):
            w.setFixedWidth(w.fontMetrics().horizontalAdvance(longest) + 16)
            (self.statusBar().addPermanentWidget if permanent else self.statusBar().addWidget)(w)
        self._connect_widgets()

    def _dock(self, title: str, widget: QWidget, area: Qt.DockWidgetArea) -> QDockWidget:
        dock = QDockWidget(title, self)
        dock.setObjectName(title)
        dock.setWidget(widget)
        self.addDockWidget(area, dock)
        return dock

    def _connect_widgets(self) -> None:
        s = self.session
        t = self.timeline
        t.playToggled.connect(s.set_playing)
        t.stepRequested.connect(s.step)
        t.seekRequested.connect(s.seek)
        t.speedChanged.connect(lambda v: s.set_playback(speed=v))
        t.loopChanged.connect(lambda v: s.set_playback(loop=v))
        t.paceChanged.connect(self._guard(lambda p: s.set_playback(pace=p)))
        sp = self.sensor_panel
        sp.presetChanged.connect(self._guard(self._set_preset))
        sp.sensorChanged.connect(self._guard(lambda j, ch: s.sensors.edit(j, **ch)))
        sp.failureRequested.connect(self._guard(s.simulate_failure))
        sp.resetRequested.connect(lambda j: s.sensors.reset_offsets(j or None))
        cp = self.constraint_panel
        cp.addRequested.connect(self._guard(self._add_constraint))
        cp.removeRequested.connect(self._guard(s.constraints.remove))
        cp.changed.connect(self._guard(self._edit_constraint))
        link_ranges(
            cp, self.timeline.set_constraint_span, lambda: s.frame, lambda: s.num_frames, self.timeline.selection
        )
        op = self.optimizer_panel
        op.settingChanged.connect(self._guard(s.set_setting))
        op.methodChanged.connect(lambda m: s.set_method(m))
        op.ghostsChanged.connect(s.set_ghosts)
        self.viewport.targetDragged.connect(self._guard(s.drag_target))
        self.viewport.jointDragged.connect(self._guard(self._drag_joint))
        self.viewport.jointSelected.connect(self._select_joint)
        self.viewport.gizmoEdited.connect(self._guard(lambda n, ch: s.constraints.edit(n, **ch)))
        self.latent.decodeRequested.connect(s.decode_latent)
        self.latent.debugToggled.connect(self._latent_debug)
        self.viewport.filesDropped.connect(self._open_dropped)

    def _guard(self, fn: Any) -> Any:
        """Wrap a request so a user error shows a dialog instead of escaping into Qt."""

        def call(*args: Any) -> None:
            try:
                fn(*args)
            except UserError as exc:
                self.show_error("Cannot apply the change", str(exc))

        return call

    def show_error(self, title: str, message: str) -> None:
        QMessageBox.critical(self, title, message)

    def _set_preset(self, name: str) -> None:
        self.session.sensors.set_preset(name)
        self._preset_chosen = True

    def _remember_preset(self) -> None:
        """Offer the preset chosen in the panel at the next start once the scene is kept
        (:attr:`SceneUndo.kept`: saved, or when asked before quitting or opening another
        clip). Written on the choice itself, a preset then undone, or discarded when
        asked, came back with the next session."""
        if self._preset_chosen and self.session.preset:
            self.settings.setValue("last_preset", self.session.preset)

    def _add_constraint(self, kind: str) -> None:
        """Add ``kind`` placed next to the character as it stands now (not at the origin),
        on the joint clicked in the 3D view, or one no ``kind`` constraint holds yet."""
        spec = self.session.constraints.catalog().get(kind)
        snap = self.session.latest
        defaults = {} if spec is None else {f.name: f.default for f in spec.fields}
        taken = {j for c in self.session.constraints if c.kind == kind for j in c.acts_on()}
        positions = None if snap is None else snap.positions
        params = placed_params(kind, defaults, positions, self.motion_paths.selected, taken)
        self.session.constraints.add(kind, **params)

    def _edit_constraint(self, name: str, changes: dict) -> None:
        """An editor's change; a constraint put on other joints is placed on them as the
        character stands now (:func:`app.constraint_placement.moved_params`)."""
        snap = self.session.latest
        current = self.session.constraints.named(name)
        self.session.constraints.edit(name, **moved_params(current, changes, None if snap is None else snap.positions))

    def _drag_joint(self, joint: str, position: Any) -> None:
        """Ctrl-drag on a joint: move its sensor target, else pin the joint there."""
        if joint in self.session.sensors:
            self.session.drag_target(joint, position)
        else:
            self.session.constraints.pin(joint, position)

    def _select_joint(self, joint: str) -> None:
        """A joint clicked (or dragged) in the 3D view: its motion path over the clip shows."""
        self.motion_paths.select(joint)
        if self.motion_paths.on:
            self.statusBar().showMessage(f"{joint}: its motion path over the clip (View > Motion paths, P)", 4000)

    def _latent_debug(self, on: bool) -> None:
        """Debug on pauses playback; off solves the frame again, which drops the decoded pose."""
        if on:
            self.session.pause()
        else:
            self.session.seek(self.session.frame)

    def toggle_play(self) -> None:
        self.session.set_playing(not self.session.playing)

    def hips(self) -> np.ndarray | None:
        """The hips of the newest snapshot (3,) metres, or None before the first one."""
        snap = self.session.latest
        return None if snap is None else snap.positions[0]

    # -- Qt events ------------------------------------------------------------------
    def dragEnterEvent(self, event: Any) -> None:
        if any(is_source_file(u.toLocalFile()) for u in event.mimeData().urls()):
            event.acceptProposedAction()

    def _open_dropped(self, paths: list[str]) -> None:
        """Open the first motion file (.bvh or .amc) of a drop (on the window or the 3D view)."""
        motion = next((p for p in paths if is_source_file(p)), None)
        if motion is None:
            self.statusBar().showMessage("Only .bvh and .amc motion files can be opened by dropping them", 5000)
        else:
            self.files.open_path(motion)

    def dropEvent(self, event: Any) -> None:
        self._open_dropped([u.toLocalFile() for u in event.mimeData().urls() if u.isLocalFile()])

    def closeEvent(self, event: Any) -> None:
        if not authoring_actions.confirm_quit(self):
            event.ignore()
            return
        if self.autosave is not None:  # closed on purpose: saved, or discarded when asked
            self.autosave.studio_closed()
        self.timer.stop()
        self.undo.kept.disconnect(self._remember_preset)
        QApplication.instance().removeEventFilter(self.camera_keys)
        self.settings.setValue("geometry", self.saveGeometry())
        self.redraw.close()
        self.live.close()
        self.trim_entry.close()
        self.undo.close()
        self.session.shutdown()
        self.files.shutdown()
        self.viewport.close()
        # the plot views drop their items here, while their plots exist: an item Qt deletes
        # with the window must not stay in a Python dict of theirs (docs/reliability.md)
        for view in (self.plots, self.latent, self.method_errors):
            view.close()
        self.latent_views.close()
        super().closeEvent(event)
