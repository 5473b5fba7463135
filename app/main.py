"""Entry point of ``dragposer-studio gui``: build the window, optionally take a screenshot."""

from __future__ import annotations

import os
import sys
from pathlib import Path
from typing import Any

from PyQt6.QtCore import QTimer
from PyQt6.QtWidgets import QApplication

from app import autosave
from app.collector import collected_between_events
from app.crash_report import CrashLog, left_reports, offer, state_folder
from app.main_window import MainWindow
from app.measure import Measurement
from engine.autosave import AutosaveSession, left_sessions
from engine.errors import UserError
from engine.startup_trace import mark

REPO = Path(__file__).resolve().parents[1]
EXAMPLE_CLIP = REPO / "assets" / "clips" / "example.bvh"
SCREENSHOT_TIMEOUT_S = 120.0


def open_initial(window: MainWindow, path: str | None, sensors: str | None, rig_map: Path | None = None) -> None:
    """Open ``path`` (with the joint mapping file ``rig_map``, ``--rig-map``), else the
    bundled example, else a procedural walk (with a message).

    ``sensors`` (a preset or a ``--sensors`` list) wins over the preset remembered from
    the last session.
    """
    from app.demo import demo_walk

    ok = False
    if path:
        ok = window.files.open_path(path, rig_map, ask=False)  # the start: nothing to lose
    elif EXAMPLE_CLIP.is_file():
        ok = window.files.open_path(EXAMPLE_CLIP, ask=False)
    if not ok:
        window.session.set_motion(demo_walk())
        window.statusBar().showMessage("No clip loaded: showing a procedural walk (File > Open a BVH)", 10000)
    # the starting sensors are where the history begins, not an edit to undo
    with window.undo.unrecorded():
        if sensors:
            window.session.sensors.set_text(sensors)
            return
        last = window.settings.value("last_preset")
        if last:
            try:
                window.session.sensors.set_preset(str(last))
            except UserError as exc:  # a preset name from an older version
                window.statusBar().showMessage(str(exc), 8000)


def apply_scene_file(window: MainWindow, scene_path: str, clip_given: bool) -> None:
    """Apply the scene file ``scene_path`` (``--scene``) to the open clip; without a clip
    on the command line the scene's own clip is opened first.

    Raises
    ------
    UserError
        A scene that cannot be read or applied, naming the file (and line or field).
    """
    from engine.input_files import read_json

    try:
        scene = read_json(scene_path, "scene")
        if not isinstance(scene, dict):
            raise UserError("a scene is a JSON object")
        clip = scene.get("clip")
        if clip and not clip_given and not window.files.open_path(str(clip), ask=False):
            raise UserError(f"cannot open its clip {clip}")
        window.session.apply_scene(scene, scene_path)
    except (OSError, ValueError) as exc:
        raise UserError(f"{scene_path}: {exc}") from exc
    except UserError as exc:
        raise UserError(str(exc) if scene_path in str(exc) else f"{scene_path}: {exc}") from exc


def start_autosave(window: MainWindow, folder: Path | None = None) -> AutosaveSession | None:
    """Autosave ``window`` (and its pose windows) into ``folder`` (default: the state
    folder, beside the crash logs: :mod:`app.autosave`); None, said in the status bar,
    when the folder cannot be written."""
    try:
        files = AutosaveSession(folder or state_folder())
    except UserError as exc:
        window.statusBar().showMessage(f"No autosave: {exc}", 15000)
        return None
    window.autosave = autosave.StudioAutosave(window, files)
    return files


def start_playing(window: MainWindow) -> None:
    """Play the clip once the window is up: opened paused on frame 0, the studio looked
    like a still picture (the engine solves the first frame, then playback runs)."""
    QTimer.singleShot(0, window.session.play)


def run(
    path: str | None = None,
    method: str = "ik",
    sensors: str | None = None,
    screenshot: str | None = None,
    after_frames: int = 60,
    measure: float | None = None,
    measure_json: str | None = None,
    pace: str | None = None,
    ghosts: tuple[str, ...] = (),
    view: str = "stick",
    rig_map: Path | None = None,
    engine: str = "process",
    scene: str | None = None,
    explicit_method: bool = True,
    started: Any = None,
) -> int:
    """Show the studio; with ``screenshot``, play ``after_frames`` frames, save and exit;
    with ``measure``, play that many seconds and write the figures to ``measure_json``
    (:mod:`app.measure`). ``pace`` sets the playback pace (every_frame or real_time).
    ``ghosts``: other methods drawn beside the reconstruction; ``view`` draws the
    reconstruction as a ``stick`` figure or a shaded ``body``; ``rig_map`` is the joint
    mapping file for ``path`` (``--rig-map``); ``engine`` runs the solver in its own
    ``process`` or in a ``thread`` of this one. ``scene`` is a saved scene applied to the
    clip (``--scene``); ``--sensors`` and an explicit ``--method`` win over the scene's.
    ``started``: the engine process :func:`app.cli.run` started before importing Qt."""
    # Mesa's software rasterizer (llvmpipe: Xvfb, no GPU) starts a thread per core; on a
    # small machine leave one core to the solver's process (set before the first GL context)
    os.environ.setdefault("LP_NUM_THREADS", str(max(1, (os.cpu_count() or 2) - 1)))
    app = QApplication.instance() or QApplication(sys.argv[:1])
    app.setApplicationName("DragPoser Studio")
    crash = CrashLog()
    reports = left_reports(crash.folder) if crash.folder.is_dir() else []
    crash.start()
    # cycles are collected between events on this thread, never inside a paint or in a
    # worker thread (app.collector); start-up runs with collection off (app.cli.run)
    try:
        with collected_between_events():
            return _run(
                app,
                path,
                method,
                sensors,
                screenshot,
                after_frames,
                measure,
                measure_json,
                pace,
                ghosts,
                view,
                rig_map,
                engine,
                scene,
                explicit_method,
                started,
                reports,
            )
    finally:
        crash.close()


def _run(
    app: QApplication,
    path: str | None,
    method: str,
    sensors: str | None,
    screenshot: str | None,
    after_frames: int,
    measure: float | None,
    measure_json: str | None,
    pace: str | None,
    ghosts: tuple[str, ...],
    view: str,
    rig_map: Path | None,
    engine: str,
    scene: str | None,
    explicit_method: bool,
    started: Any,
    reports: list[Path],
) -> int:
    window = MainWindow(method=method, engine=engine, started=started)
    mark("window built")
    try:
        open_initial(window, path if path or not scene else None, sensors, rig_map)
        if scene:
            apply_scene_file(window, scene, clip_given=bool(path))
            if sensors:
                window.session.sensors.set_text(sensors)
            if explicit_method and method != window.session.method:
                with window.undo.unrecorded():  # the command line's choice: the start, not an edit
                    window.session.set_method(method)
        if ghosts:  # comparing methods: show their errors rather than the optimizer's losses
            with window.undo.unrecorded():
                window.session.set_method(window.session.method, ghosts)
            window.method_errors_dock.raise_()
    except UserError:
        window.close()
        raise
    if pace is not None:
        window.session.set_playback(pace=pace)
    window.actions_by_name[f"display-{view}"].setChecked(True)
    window.undo.set_clean()  # what the command line set up is the start, nothing to save
    if screenshot is not None:
        window.resize(1600, 980)  # a reproducible layout, whatever geometry was saved
    if measure is not None:
        window.resize(1600, 1000)  # the layout the targets are set for
    window.show()
    mark("window shown")
    if measure is not None:
        return _measure(app, window, measure, measure_json)
    if screenshot is None:
        files = start_autosave(window)
        left = left_sessions(files.folder) if files is not None else []
        start_playing(window)
        QTimer.singleShot(0, lambda: setattr(window, "crash_box", offer(window, reports)))
        QTimer.singleShot(0, lambda: setattr(window, "recovery_box", autosave.offer(window, left)))
        try:
            return app.exec()
        finally:
            if files is not None:
                files.close()  # a clean quit: nothing to recover next time
    status = {"code": 1}
    start = window.session.frame
    stepped = {"to": start}

    # frame by frame (each step solved like a played frame, in order), so exactly
    # ``after_frames`` are played: a pause sent after the window draws its last one
    # arrives when the engine has solved 4-6 more
    def check(frame: int) -> None:
        snap = window.session.latest
        last = snap is not None and snap.num_frames > 0 and frame >= snap.num_frames - 1
        if frame - start < after_frames and not last:
            if frame == stepped["to"]:
                advance(frame + 1)
            return
        window.snapshotDrawn.disconnect(check)
        QTimer.singleShot(200, finish)

    def finish() -> None:
        status["code"] = 0 if window.files.export_screenshot(screenshot) else 1
        mark("screenshot saved")
        window.close()
        mark("window closed (engine stopped)")
        app.quit()

    def timeout() -> None:
        print(f"error: the engine did not reach frame {after_frames} in time", file=sys.stderr)
        finish()

    def advance(frame: int) -> None:
        stepped["to"] = frame
        window.session.seek(frame)  # the next frame: solved in order, not a jump

    window.session.pause()
    window.snapshotDrawn.connect(check)
    QTimer.singleShot(300, lambda: advance(start + 1))
    QTimer.singleShot(int(SCREENSHOT_TIMEOUT_S * 1000), timeout)
    app.exec()
    return status["code"]


def _measure(app: QApplication, window: MainWindow, seconds: float, out: str | None) -> int:
    status = {"code": 1}

    def done(code: int, message: str) -> None:
        if message:
            print(message, file=sys.stderr)
        status["code"] = code
        window.close()
        app.quit()

    measurement = Measurement(window, seconds, out or "measure.json", done)
    QTimer.singleShot(300, measurement.begin)
    app.exec()
    if status["code"] == 0:
        print(f"wrote {out}")
    return status["code"]
