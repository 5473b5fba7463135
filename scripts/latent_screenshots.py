"""The latent map dock's screenshots for docs/latent.md, made by the app itself.

Opens the studio on the bundled clip with DragPoser and head, hands and hips trackers
(preset 4) plus a look-at constraint (the bundled look/floor/pin/distance scene), plays
``FRAMES`` frames, pauses, then saves the window with the dock's *Map* tab (after a click
beside the trajectory decodes that point as the white debug pose), its *Forces* tab
(after *Inspect this frame* with the left wrist chosen), its *Gallery* tab and the *Map*
tab again with the inspected forces drawn in the map plane.

    PYTHONPATH=. xvfb-run -a -s "-screen 0 1600x1000x24" python scripts/latent_screenshots.py docs/images
        [--frames 150] [--scene assets/scenes/look_floor_pin_distance.json]

Prints the time from the click to the decoded pose's snapshot.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np
from PyQt6.QtCore import QSettings, Qt
from PyQt6.QtTest import QTest
from PyQt6.QtWidgets import QApplication


def wait(app: QApplication, cond, timeout: float = 120.0) -> None:
    end = time.monotonic() + timeout
    while not cond():
        if time.monotonic() > end:
            raise SystemExit("timed out waiting for the studio")
        app.processEvents()
        time.sleep(0.01)


def main() -> int:
    p = argparse.ArgumentParser()
    p.add_argument("out", type=Path)
    p.add_argument("--frames", type=int, default=150)
    p.add_argument("--scene", default="assets/scenes/look_floor_pin_distance.json")
    args = p.parse_args()
    app = QApplication(sys.argv)
    from app.main_window import MainWindow

    settings = QSettings(str(args.out / ".latent-shots.ini"), QSettings.Format.IniFormat)
    w = MainWindow(method="dragposer", settings=settings, engine="thread")
    w.resize(1600, 1000)
    w.show()
    s = w.session
    w.files.open_path("assets/clips/example.bvh", ask=False)
    if args.scene:
        w.files.load_scene(args.scene)
    s.sensors.set_preset("4")
    wait(app, lambda: s.latest is not None and s.latest.latent_view is not None)
    s.play()
    wait(app, lambda: s.latest.frame >= args.frames)
    s.pause()
    v = w.latent_views
    v.dock.raise_()
    scene = next(d for d in w.findChildren(type(v.dock)) if d.objectName() == "Scene")
    w.resizeDocks([scene, v.dock], [260, 700], Qt.Orientation.Vertical)
    v.tabs.setCurrentIndex(0)
    wait(app, lambda: len(v.map.xy) > 10)
    for _ in range(20):
        app.processEvents()
        time.sleep(0.02)
    view = s.latest.latent_view
    seq = s.latest.seq
    v.map.plot.repaint()
    t0 = time.perf_counter()
    QTest.mouseClick(
        v.map.plot.viewport(), Qt.MouseButton.LeftButton, pos=v.map.to_widget(*(view.xy + [1.2, 0.9])).toPoint()
    )
    wait(app, lambda: s.latest.seq > seq and s.latest.decoded is not None)
    print(f"click to decoded snapshot: {1000 * (time.perf_counter() - t0):.1f} ms")
    for _ in range(30):
        app.processEvents()
        time.sleep(0.02)
    w.files.export_screenshot(str(args.out / "latent-map.png"))
    v.tabs.setCurrentIndex(1)
    v.forces.joint.setCurrentIndex(v.forces.joint.findData("lwrist"))
    QTest.mouseClick(v.forces.inspect_button, Qt.MouseButton.LeftButton)
    wait(app, lambda: v.forces.detail is not None)
    d = v.forces.detail
    print(f"inspect: {d.ms:.0f} ms on the engine")
    lv = s.latest.latent_view
    print(f"frame {lv.frame}: nearest {lv.nearest:.2f} norm {lv.norm:.2f} prior {lv.predictor:.2f} start {lv.start}")
    norms = dict(zip(d.names, np.linalg.norm(d.forces[0], axis=1).round(3)))
    print("force norms at iteration 0:", norms)
    print("conflicts:", v.forces.info.text())
    print(
        "most influential dimensions on the left wrist:",
        v.gallery.influential or list(np.argsort(d.influence)[::-1][:5]),
    )
    for _ in range(30):
        app.processEvents()
        time.sleep(0.02)
    w.files.export_screenshot(str(args.out / "latent-forces.png"))
    v.tabs.setCurrentIndex(2)
    for _ in range(30):
        app.processEvents()
        time.sleep(0.02)
    w.files.export_screenshot(str(args.out / "latent-gallery.png"))
    v.tabs.setCurrentIndex(0)  # the forces in the map plane
    for _ in range(30):
        app.processEvents()
        time.sleep(0.02)
    w.files.export_screenshot(str(args.out / "latent-map-forces.png"))
    w.undo.set_clean()
    w.close()
    return 0


if __name__ == "__main__":
    sys.exit(main())
