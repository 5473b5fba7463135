"""Entry point of ``dragposer-studio gui``: build the window, optionally take a screenshot."""

from __future__ import annotations

import os
import sys
from pathlib import Path

from PyQt6.QtCore import QTimer
from PyQt6.QtWidgets import QApplication

from app.main_window import MainWindow
from app.measure import Measurement
from engine.errors import UserError

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
        ok = window.files.open_path(path, rig_map)
    elif EXAMPLE_CLIP.is_file():
        ok = window.files.open_path(EXAMPLE_CLIP)
    if not ok:
        window.session.set_motion(demo_walk())
        window.statusBar().showMessage("No clip loaded: showing a procedural walk (File > Open a BVH)", 10000)
    if sensors:
        window.session.set_sensor_text(sensors)
        return
    last = window.settings.value("last_preset")
    if last:
        try:
            window.session.set_preset(str(last))
        except UserError as exc:  # a preset name from an older version
            window.statusBar().showMessage(str(exc), 8000)


def run(path: str | None = None, method: str = "ik", sensors: str | None = None,
        screenshot: str | None = None, after_frames: int = 60, measure: float | None = None,
        measure_json: str | None = None, pace: str | None = None, ghosts: tuple[str, ...] = (),
        view: str = "stick", rig_map: Path | None = None, engine: str = "process") -> int:  # fmt: skip
    """Show the studio; with ``screenshot``, play ``after_frames`` frames, save and exit;
    with ``measure``, play that many seconds and write the figures to ``measure_json``
    (:mod:`app.measure`). ``pace`` sets the playback pace (every_frame or real_time).
    ``ghosts``: other methods drawn beside the reconstruction; ``view`` draws the
    reconstruction as a ``stick`` figure or a shaded ``body``; ``rig_map`` is the joint
    mapping file for ``path`` (``--rig-map``); ``engine`` runs the solver in its own
    ``process`` or in a ``thread`` of this one."""
    # Mesa's software rasterizer (llvmpipe: Xvfb, no GPU) starts a thread per core; on a
    # small machine leave one core to the solver's process (set before the first GL context)
    os.environ.setdefault("LP_NUM_THREADS", str(max(1, (os.cpu_count() or 2) - 1)))
    app = QApplication.instance() or QApplication(sys.argv[:1])
    app.setApplicationName("DragPoser Studio")
    window = MainWindow(method=method, engine=engine)
    try:
        open_initial(window, path, sensors, rig_map)
        if ghosts:  # comparing methods: show their errors rather than the optimizer's losses
            window.session.set_method(window.session.method, ghosts)
            window.method_errors_dock.raise_()
    except UserError:
        window.close()
        raise
    if pace is not None:
        window.session.set_playback(pace=pace)
    window.actions_by_name[f"display-{view}"].setChecked(True)
    if screenshot is not None:
        window.resize(1600, 980)  # a reproducible layout, whatever geometry was saved
    if measure is not None:
        window.resize(1600, 1000)  # the layout the targets are set for
    window.show()
    if measure is not None:
        return _measure(app, window, measure, measure_json)
    if screenshot is None:
        return app.exec()
    status = {"code": 1}
    start = window.session.frame

    def check(frame: int) -> None:
        snap = window.session.latest
        ended = snap is not None and snap.seq > 0 and not snap.playing and frame > start
        if frame - start < after_frames and not ended:
            return
        window.snapshotDrawn.disconnect(check)
        window.session.pause()
        QTimer.singleShot(200, finish)

    def finish() -> None:
        status["code"] = 0 if window.files.export_screenshot(screenshot) else 1
        window.close()
        app.quit()

    def timeout() -> None:
        print(f"error: the engine did not reach frame {after_frames} in time", file=sys.stderr)
        finish()

    window.snapshotDrawn.connect(check)
    window.session.set_playback(loop=False)
    QTimer.singleShot(300, window.session.play)
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
