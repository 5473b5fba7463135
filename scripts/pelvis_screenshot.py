"""docs/images/pelvis_only.png: the pose window after Shift + drag of the hips 35 cm down
and 12 cm back (as a person sits back into a squat), made with real input from xdotool
(Shift held, the hips pressed and dragged down the screen in the side view), then saved
by the window; prints what the drag did.

    PYTHONPATH=. xvfb-run -a -s "-screen 0 1600x1000x24" python scripts/pelvis_screenshot.py \\
        docs/images/pelvis_only.png
"""

import subprocess
import sys

import numpy as np
from PyQt6.QtCore import QPoint, QTimer
from PyQt6.QtWidgets import QApplication

from app.pose_window import PoseWindow
from engine import skeleton as sk
from engine.authoring.pose_mode import PoseMode
from engine.authoring.session import AuthoringSession
from engine.models import load_default_models

DOWN = 0.35  # metres the hips are dragged down
BACK = 0.12  # ... and back (+Y: the character faces -Y)
STEPS = 12  # mouse moves of the drag
FEET = [sk.JOINT_INDEX[j] for j in ("lankle", "ltoe", "rankle", "rtoe")]

app = QApplication(sys.argv)
w = PoseWindow(AuthoringSession(PoseMode(load_default_models().vae, 1.75)))
w.resize(1400, 860)
w.show()
for _ in range(5):
    app.processEvents()
w.viewport.set_camera("side", w.hips())
cam = w.viewport.plotter.camera
down = np.array([0.0, 0.0, 0.3])  # the view centred on the squat to come
cam.focal_point, cam.position = tuple(np.array(cam.focal_point) - down), tuple(np.array(cam.position) - down)
cam.zoom(1.4)
w.viewport.plotter.render()
before = w.mode.pose


def on_screen(point: np.ndarray) -> tuple[int, int]:
    """The X screen pixel of world ``point (3,)``."""
    x, y = w.viewport.joints._to_display(np.asarray(point, float)[None])[0]
    widget = w.viewport.plotter
    g = widget.mapToGlobal(QPoint(int(round(x)), int(round(widget.height() - 1 - y))))
    return g.x(), g.y()


(x0, y0), (x1, y1) = on_screen(before.positions[0]), on_screen(before.positions[0] + [0.0, BACK, -DOWN])
moves = [
    f"mousemove {round(x0 + (x1 - x0) * k / STEPS)} {round(y0 + (y1 - y0) * k / STEPS)} sleep 0.15"
    for k in range(1, STEPS + 1)
]
script = f"keydown shift mousemove {x0} {y0} sleep 0.2 mousedown 1 sleep 0.2 {' '.join(moves)} mouseup 1 keyup shift"
drag = subprocess.Popen(["xdotool", *script.split()])
status: list[str] = []


def wait() -> None:
    status.append(w.statusBar().currentMessage())
    if drag.poll() is None:
        QTimer.singleShot(50, wait)
        return
    for _ in range(5):
        app.processEvents()
    after = w.mode.pose
    print(
        f"pelvis {before.root_pos.round(3)} -> {after.root_pos.round(3)}; feet moved "
        f"{1000 * np.abs(after.positions[FEET] - before.positions[FEET]).max():.3f} mm; "
        f"root target pelvis_only: {getattr(w.mode.targets.get('root'), 'pelvis_only', None)}; "
        f"status seen: {sorted(set(s for s in status if s))}"
    )
    w.deselect()
    w.statusBar().showMessage("Pelvis only: feet planted")
    for _ in range(5):
        app.processEvents()
    ok = w.files.screenshot(sys.argv[1] if len(sys.argv) > 1 else "pelvis_only.png")
    w.session.history.set_clean()
    w.close()
    app.exit(0 if ok else 1)


QTimer.singleShot(100, wait)
sys.exit(app.exec())
