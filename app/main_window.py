"""The studio's main window: wires the session, the engine thread and the widgets.

Data flow: widgets emit requests -> the window calls :class:`engine.session.Session`
methods -> the session forwards commands to :class:`engine.worker.EngineWorker`. The
worker publishes snapshots; a display-rate QTimer draws only the newest one, so the GUI
never waits on the engine. Session events refresh the panels.
"""

from __future__ import annotations

import gc
import sys
import time
from typing import Any

from PyQt6.QtCore import QSettings, Qt, QTimer, pyqtSignal
from PyQt6.QtWidgets import QDockWidget, QLabel, QMainWindow, QMessageBox, QTabWidget, QVBoxLayout, QWidget

from app.file_actions import FileActions
from app.menus import build_menus
from app.schema import constraint_schema, load_constraint_kinds, optimizer_choices
from engine.errors import UserError
from engine.session import Session, sensor_presets
from engine.worker import DecodeLatent, EngineWorker
from widgets.constraint_panel import ConstraintPanel
from widgets.latent_inspector import LatentInspector
from widgets.optimizer_panel import OptimizerPanel
from widgets.plots import LossPlots
from widgets.sensor_panel import SensorPanel
from widgets.timeline import Timeline
from widgets.viewport import Viewport



def method_names(current: str) -> list[str]:
    """Registered methods (plus ``current``, so an unknown one is shown, not hidden)."""
    try:
        from engine.methods import available_methods
    except ImportError:
        names: list[str] = []
    else:
        names = list(available_methods())
    return names + ([current] if current not in names else [])

DRAW_INTERVAL_MS = 16  # at most ~60 redraws per second
MAX_DRAW_INTERVAL_MS = 150  # never fewer than ~6 redraws per second
#: Plots, status bar and other chrome redraw at ~8 Hz while playing: under Xvfb a
#: widget repaint costs more than the whole 3D view.
PLOT_INTERVAL_S = 0.12


class MainWindow(QMainWindow):
    """The studio. ``snapshotDrawn(int)`` fires after each drawn snapshot (its frame)."""

    snapshotDrawn = pyqtSignal(int)

    def __init__(self, method: str = "ik", settings: QSettings | None = None) -> None:
        super().__init__()
        self.setWindowTitle("DragPoser Studio")
        self.setAcceptDrops(True)
        self.settings = settings or QSettings("dragposer-studio", "studio")
        self.kinds = load_constraint_kinds()
        self.session = Session(method=method)
        self.worker = EngineWorker()
        self._build_widgets()
        self.worker.start()  # after the widgets: the thread's first imports would compete
        self.session.attach(self.worker.submit)
        self.files = FileActions(self)
        build_menus(self)
        self._unsubscribe = self.session.subscribe(self._on_session)
        self._refresh_panels()
        self._drawn_seq, self._draws, self._draw_rate, self._rate_t0 = -1, 0, 0.0, time.monotonic()
        self._plotted_at, self._panel_seq, self._last_was_view = 0.0, -1, False
        self._last_tick = time.perf_counter()
        self.timer = QTimer(self, interval=DRAW_INTERVAL_MS)
        self.timer.timeout.connect(self._draw)
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
        self.sensor_panel = SensorPanel(sensor_presets())
        self.constraint_panel = ConstraintPanel(constraint_schema(self.kinds))
        choices, self._optimizer_defaults = optimizer_choices()
        self.optimizer_panel = OptimizerPanel(method_names(self.session.method), choices)
        tabs = QTabWidget()
        tabs.addTab(self.sensor_panel, "Sensors")
        tabs.addTab(self.constraint_panel, "Constraints")
        tabs.addTab(self.optimizer_panel, "Optimizer")
        self.latent = LatentInspector()
        self.plots = LossPlots()
        scene = self._dock("Scene", tabs, Qt.DockWidgetArea.RightDockWidgetArea)
        latent = self._dock("Latent", self.latent, Qt.DockWidgetArea.RightDockWidgetArea)
        plots = self._dock("Optimizer plots", self.plots, Qt.DockWidgetArea.BottomDockWidgetArea)
        # the right column runs the full height, so the latent dock has room for its
        # 24-row history strip; the plots sit under the 3D view only
        self.setCorner(Qt.Corner.BottomRightCorner, Qt.DockWidgetArea.RightDockWidgetArea)
        self.resizeDocks([scene, latent], [430, 430], Qt.Orientation.Horizontal)
        self.resizeDocks([scene, latent], [480, 420], Qt.Orientation.Vertical)
        self.resizeDocks([plots], [300], Qt.Orientation.Vertical)
        self.status_engine = QLabel()
        self.status_gui = QLabel()
        self.status_warnings = QLabel()
        for w, width in ((self.status_engine, 330), (self.status_gui, 120), (self.status_warnings, 110)):
            w.setFixedWidth(width)  # text changes must not relayout the window every frame
            self.statusBar().addPermanentWidget(w)
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
        t.playToggled.connect(lambda on: s.play() if on else s.pause())
        t.stepRequested.connect(s.step)
        t.seekRequested.connect(s.seek)
        t.speedChanged.connect(lambda v: s.set_playback(speed=v))
        t.loopChanged.connect(lambda v: s.set_playback(loop=v))
        sp = self.sensor_panel
        sp.presetChanged.connect(self._guard(self._set_preset))
        sp.sensorChanged.connect(self._guard(lambda j, ch: s.update_sensor(j, **ch)))
        sp.failureRequested.connect(self._guard(s.simulate_failure))
        sp.resetRequested.connect(lambda j: s.reset_offsets(j or None))
        cp = self.constraint_panel
        cp.addRequested.connect(self._guard(self._add_constraint))
        cp.removeRequested.connect(s.remove_constraint)
        cp.changed.connect(self._guard(lambda n, ch: s.update_constraint(n, **ch)))
        op = self.optimizer_panel
        op.settingChanged.connect(s.set_setting)
        op.methodChanged.connect(lambda m: s.set_method(m))
        op.ghostsChanged.connect(lambda g: s.set_method(s.method, g))
        self.viewport.targetDragged.connect(self._guard(s.drag_target))
        self.viewport.jointDragged.connect(self._guard(self._drag_joint))
        self.viewport.gizmoEdited.connect(self._guard(lambda n, ch: s.update_constraint(n, **ch)))
        self.latent.decodeRequested.connect(lambda z: self.worker.submit(DecodeLatent(z)))
        self.latent.debugToggled.connect(self._latent_debug)
        self.viewport.filesDropped.connect(self._open_dropped)

    # -- session -> widgets -------------------------------------------------------------
    def _on_session(self, event: str, data: Any) -> None:
        if event == "frame":
            self.timeline.set_frame(int(data))
        elif event == "playing":
            self.timeline.set_playing(bool(data))
        elif event == "motion":
            self.timeline.set_range(self.session.num_frames, data.fps)
            self.plots.clear()
            self.viewport.reset_camera(data.root_pos[0])
        if event in ("sensors", "constraints", "settings", "method", "motion"):
            self._refresh_panels()

    def _refresh_panels(self) -> None:
        s = self.session
        self.viewport.oriented = frozenset(j for j, c in s.sensors.items() if c.dof == 6)
        self.sensor_panel.set_sensors(s.preset, s.sensors)
        self.constraint_panel.set_constraints([c.to_dict() for c in s.constraints])
        # settings the session has not set yet show the engine's defaults
        self.optimizer_panel.set_state(s.method, s.ghosts, {**self._optimizer_defaults, **s.settings})

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
        self.session.set_preset(name)
        self.settings.setValue("last_preset", name)

    def _add_constraint(self, kind: str) -> None:
        cls = self.kinds.get(kind)
        if cls is None:
            raise UserError(f"unknown constraint kind {kind!r}")
        try:
            constraint = cls()
        except TypeError as exc:
            raise UserError(f"{kind}: cannot create with default parameters ({exc})") from exc
        self.session.add_constraint(constraint)

    def _drag_joint(self, joint: str, position: Any) -> None:
        """Ctrl-drag on a joint: move its sensor target, else pin it with a point constraint."""
        s = self.session
        if joint in s.sensors:
            s.drag_target(joint, position)
            return
        schema = constraint_schema(self.kinds)
        # the engine's "pin" kind first; else any kind with a joint and a point to drag
        order = sorted(schema.items(), key=lambda kv: kv[0] != "pin")
        pin = next(((k, f) for k, fields in order if any(n == "joint" for n, _, _ in fields)
                    for f, tag, _ in fields if tag == "vec3" and f in ("target", "position", "point")), None)  # fmt: skip
        if pin is None:
            self.statusBar().showMessage(f"No sensor on {joint} and no point-constraint kind to pin it", 5000)
            return
        kind, field = pin
        name = f"drag {joint}"
        if any(c.name == name for c in s.constraints):
            s.update_constraint(name, **{field: position})
            return
        constraint = self.kinds[kind]()
        constraint.name, constraint.joint = name, joint
        setattr(constraint, field, position)
        s.add_constraint(constraint)

    def _latent_debug(self, on: bool) -> None:
        """Debug on pauses playback; off solves the frame again, which drops the decoded pose."""
        if on:
            self.session.pause()
        else:
            self.session.seek(self.session.frame)

    def toggle_play(self) -> None:
        self.session.pause() if self.session.playing else self.session.play()

    def hips(self) -> Any:
        """The hips of the newest snapshot (3,) metres, or None before the first one."""
        snap = self.worker.latest
        return None if snap is None else snap.positions[0]

    # -- drawing --------------------------------------------------------------------
    def _draw(self) -> None:
        """One display tick: draw the 3D view *or* refresh the panels, never both.

        Splitting the work keeps every tick short (on software GL a full redraw of view,
        plots and labels exceeds 50 ms), and the interval stretches with the measured
        cost so drawing never takes more than about two thirds of the event loop.
        """
        t0 = time.perf_counter()
        snap = self.worker.latest
        now = time.monotonic()
        if now - self._rate_t0 >= 1.0:
            self._draw_rate, self._draws, self._rate_t0 = self._draws / (now - self._rate_t0), 0, now
        if snap is None:
            return
        panels_due = snap.seq != self._panel_seq and (now - self._plotted_at >= PLOT_INTERVAL_S or not snap.playing)
        if snap.seq != self._drawn_seq and not (panels_due and self._last_was_view):
            self._drawn_seq = snap.seq
            self._draws += 1
            self.viewport.show_snapshot(snap)
            self._last_was_view = True
            self.snapshotDrawn.emit(snap.frame)
        elif panels_due:
            self._plotted_at, self._panel_seq, self._last_was_view = now, snap.seq, False
            self._update_panels(snap)
        self._pace(t0, (time.perf_counter() - t0) * 1000.0)

    def _pace(self, t0: float, cost_ms: float) -> None:
        """Stretch the draw interval when the event loop is saturated, relax it after.

        Much of a redraw's cost is paid after this method returns (Qt composites the
        window), so the tick-to-tick period is the honest measure of the loop's load.
        """
        period_ms = (t0 - self._last_tick) * 1000.0
        self._last_tick = t0
        interval = self.timer.interval()
        if period_ms > 1.2 * interval or 1.5 * cost_ms > interval:
            interval = min(MAX_DRAW_INTERVAL_MS, int(1.3 * max(period_ms, cost_ms)))
        else:
            interval = max(DRAW_INTERVAL_MS, int(0.9 * interval))
        self.timer.setInterval(interval)

    def _update_panels(self, snap: Any) -> None:
        self.session.note_frame(snap.frame)
        self.plots.update_snapshot(snap)
        self.latent.update_snapshot(snap)
        if self.session.playing and not snap.playing:  # reached the end without looping
            self.session.playing = False
            self.timeline.set_playing(False)
        self.status_engine.setText(f"engine {snap.engine_fps:5.1f} frames/s   {snap.ms:6.1f} ms/frame   "
                                   f"{snap.iterations} it")  # fmt: skip
        self.status_gui.setText(f"GUI {self._draw_rate:4.0f} draws/s")
        self.status_warnings.setText(f"warnings {snap.warnings}")
        self.status_warnings.setToolTip(snap.error or "\n".join(snap.messages))
        if snap.error:
            self.statusBar().showMessage(snap.error, 5000)
        if snap.method_error:  # the engine kept its method: show it, then say why
            self.session.method = snap.method
            self._refresh_panels()
            self.show_error("Cannot switch method", snap.method_error)

    # -- Qt events ------------------------------------------------------------------
    def dragEnterEvent(self, event: Any) -> None:
        if any(u.toLocalFile().lower().endswith(".bvh") for u in event.mimeData().urls()):
            event.acceptProposedAction()

    def _open_dropped(self, paths: list[str]) -> None:
        """Open the first .bvh of a drop (on the window or the 3D view)."""
        bvh = next((p for p in paths if p.lower().endswith(".bvh")), None)
        if bvh is None:
            self.statusBar().showMessage("Only .bvh motion files can be opened by dropping them", 5000)
        else:
            self.files.open_path(bvh)

    def dropEvent(self, event: Any) -> None:
        self._open_dropped([u.toLocalFile() for u in event.mimeData().urls() if u.isLocalFile()])

    def closeEvent(self, event: Any) -> None:
        self.timer.stop()
        self.settings.setValue("geometry", self.saveGeometry())
        self._unsubscribe()
        self.worker.stop()
        self.files.shutdown()
        self.viewport.close()
        super().closeEvent(event)
