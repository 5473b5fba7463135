"""The pose and key window's screenshots for docs/authoring.md, made by the app itself.

Poses the 1.75 m character (left wrist raised and forward, right wrist out), keys it at
frame 0, moves the body 0.6 m forward and turns it 30 degrees, keys that at frame 40,
scrubs to frame 20 (an in-between) and selects the left wrist (its rotation rings show),
then saves the window. With a second path, also the head turned 40 degrees by its
vertical ring, seen from above.

    PYTHONPATH=. xvfb-run -a -s "-screen 0 1600x1000x24" python scripts/authoring_screenshot.py \\
        docs/images/authoring.png docs/images/authoring_rings.png
"""

import sys

import numpy as np
from PyQt6.QtWidgets import QApplication

from app.pose_window import PoseWindow
from engine import skeleton as sk
from engine.authoring.pose_mode import PoseMode
from engine.authoring.session import AuthoringSession
from engine.models import load_default_models

app = QApplication(sys.argv)
vae = load_default_models().vae


def window() -> PoseWindow:
    w = PoseWindow(AuthoringSession(PoseMode(vae, 1.75)))
    w.resize(1400, 860)
    w.show()
    return w


def save(w: PoseWindow, path: str) -> bool:
    for _ in range(5):
        app.processEvents()
    ok = w.files.screenshot(path)
    w.session.history.set_clean()
    w.close()
    return ok


w = window()
lw, rw = (w.mode.pose.positions[sk.JOINT_INDEX[j]].copy() for j in ("lwrist", "rwrist"))
for k in range(1, 11):
    w.drag_joint("lwrist", lw + np.array([0.0, -0.15, 0.05]) * k / 10)
w.add_key(0)
w.clear_all()
w.move_body(np.array([0.0, -0.6, 0.0]))
w.turn_body(30.0)
lw, rw = (w.mode.pose.positions[sk.JOINT_INDEX[j]].copy() for j in ("lwrist", "rwrist"))
for k in range(1, 21):
    w.drag_joint("lwrist", lw + np.array([0.05, -0.25, 0.55]) * k / 20)
    w.drag_joint("rwrist", rw + np.array([-0.25, -0.1, 0.25]) * k / 20)
w.settle()
w.add_key(40)
w.keys.length.setValue(61)
w.go_to(20)
w.selected = "lwrist"
w.refresh()
w.viewport.set_camera("home", w.hips())
ok = save(w, sys.argv[1] if len(sys.argv) > 1 else "authoring.png")
if len(sys.argv) > 2:
    w = window()
    head = w.mode.pose.positions[sk.JOINT_INDEX["upperneck"]].copy()
    w.drag_joint("upperneck", head)
    w.turns.by_ring(2, 0.0, True)
    w.turns.by_ring(2, np.radians(40.0), False)
    w.viewport.set_camera("top", w.hips())
    w.viewport.plotter.camera.zoom(2.5)
    ok = save(w, sys.argv[2]) and ok
sys.exit(0 if ok else 1)
